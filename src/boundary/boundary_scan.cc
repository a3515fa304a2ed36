#include "boundary/boundary_scan.h"

#include <vector>

#include "db/boundary_table.h"
#include "mesh/face_neighbors.h"
#include "mesh/mesh_reader.h"

namespace weaver::boundary_scan {
namespace {

// The face's two in-plane axes, in x, y, z order.
void face_axes(int face, int* u, int* v) {
  const int axis = face / 2;
  *u = axis == 0 ? 1 : 0;
  *v = axis == 2 ? 1 : 2;
}

class BoundaryWriter {
 public:
  BoundaryWriter(BoundarySink out, const Span& span, BoundaryResult* r)
      : out_(std::move(out)), span_(span), r_(r) {}

  // The boundary records of element id (octant o), in key order.
  Status element(uint64_t id, const Octant& o, FaceFinder* finder, const GroundCheck& ground) {
    const uint32_t e = octant_edge(o), c[3] = {o.x, o.y, o.z};
    std::array<bool, 6> on_side{};
    for (int f = 0; f < 6; ++f) {
      const int a = f / 2;
      on_side[f] = (f & 1) ? c[a] + e == span_.hi[a] : c[a] == span_.lo[a];
    }
    if (span_.filled) {  // nothing open inside the box: its sides alone
      for (int f = 0; f < 6; ++f) {
        if (!on_side[f]) continue;
        WEAVER_RETURN_IF_ERROR(
            emit(id, f, 0, f == 4 ? BoundaryKind::kFreeSurface : BoundaryKind::kDomainSide));
      }
      return Status::Ok();
    }
    std::array<uint8_t, 6> missing{};  // per face: bit p set when part p lies open
    const unsigned open = ground.buried(o) ? 0 : ground.open_faces(o);
    if (open != 0) {
      ++r_->asked;
      neighbours_.clear();
      WEAVER_RETURN_IF_ERROR(finder->find(o, &neighbours_, open));
      std::array<uint8_t, 6> covered{};  // bit q: quarter q (0-3) has an element
      std::array<bool, 6> whole{};
      for (const FaceNeighbor& n : neighbours_) {
        if (n.octant.level <= o.level) {
          whole[n.face] = true;
          continue;
        }
        int u, v;
        face_axes(n.face, &u, &v);
        const uint32_t nc[3] = {n.octant.x, n.octant.y, n.octant.z};
        const int qu = nc[u] - c[u] >= e / 2, qv = nc[v] - c[v] >= e / 2;
        covered[n.face] |= uint8_t(1u << (qu + 2 * qv));
      }
      for (int f = 0; f < 6; ++f) {
        if (on_side[f] || whole[f] || (open >> f & 1) == 0) continue;
        missing[f] = covered[f] == 0 ? 1 : uint8_t((~covered[f] & 15u) << 1);
      }
    }
    for (int f = 0; f < 6; ++f) {
      if (on_side[f]) {
        WEAVER_RETURN_IF_ERROR(
            emit(id, f, 0, f == 4 ? BoundaryKind::kFreeSurface : BoundaryKind::kDomainSide));
        continue;
      }
      for (int part = 0; part <= 4; ++part) {
        if (missing[f] & (1u << part)) {
          WEAVER_RETURN_IF_ERROR(emit(id, f, part, BoundaryKind::kFreeSurface));
        }
      }
    }
    return Status::Ok();
  }

 private:
  Status emit(uint64_t id, int face, int part, BoundaryKind kind) {
    const uint64_t key = boundary_key(id, face, part);
    const uint8_t k = static_cast<uint8_t>(kind);
    ++r_->faces;
    r_->quarters += part != 0;
    r_->free_surface += kind == BoundaryKind::kFreeSurface;
    return out_(key, k);
  }

  BoundarySink out_;
  const Span& span_;
  BoundaryResult* r_;
  std::vector<FaceNeighbor> neighbours_;
};

}  // namespace

Status share_of(BTree& octants, uint64_t first, uint64_t stop, const Field* vp, Share* s) {
  return walk_leaves(octants, first, stop, vp, &s->least_dt, &s->least_dt_element,
                     [s](uint64_t, const Octant& leaf) {
                       s->span.add(leaf);
                       return Status::Ok();
                     });
}

void load_ground(BTree& octants, const Span& span, MemoryBudget surface, GroundCheck* ground) {
  if (span.filled) return;
  Units units;
  units_from_metadata(octants.options().metadata, &units);
  ground->load(octants.options().metadata, units, surface);
}

// The boundary records of the elements with ids [first, stop) of the
// octant table, into `out` in key order, the leaves spanning `span`
// (settled); with vp, their least edge / vp is found on the way.  When
// full() says so after an element, stops there; *reached: the first id
// not done.
Status derive_records(BTree& octants, const BoundarySink& out, const Span& span,
                      const GroundCheck& ground, uint64_t first, uint64_t stop, const Field* vp,
                      Tally* tally, bool reports, const std::function<bool()>& full,
                      uint64_t* reached, BoundaryResult* r) {
  r->filled = span.filled;
  *reached = first;
  FaceFinder finder(octants);
  BoundaryWriter w(out, span, r);
  double least = HUGE_VAL;
  const Status st = walk_leaves(
      octants, first, stop, vp, &least, &r->least_dt_element, [&](uint64_t id, const Octant& leaf) {
        WEAVER_RETURN_IF_ERROR(w.element(id, leaf, &finder, ground));
        ++r->elements;
        *reached = id + 1;
        if ((id & 0xFFFFF) == 0xFFFFF) {
          const uint64_t done = tally->done.fetch_add(0x100000) + 0x100000;
          if (reports && tally->report) tally->report(done, double(done) / double(tally->total));
        }
        return full && full() ? Status::Busy("full") : Status::Ok();
      });
  if (!st.ok() && st.code() != Status::Code::kBusy) return st;
  r->least_dt = vp != nullptr && r->elements > 0 ? least : 0;
  return Status::Ok();
}

TableOptions boundary_table_options(bool packed) {
  TableOptions t;
  t.key_kind = KeyKind::kNode;
  std::string error;
  t.schema = *RecordSchema::parse(kBoundarySchema, &error);
  t.packed = packed;
  return t;
}

// The boundary table's metadata: its counts and least edge / vp.
std::string boundary_metadata(const BoundaryResult& r) {
  char meta[256];
  std::snprintf(meta, sizeof meta,
                "faces=%llu;free_surface=%llu;sides=%llu;least_dt=%.17g;least_dt_element=%llu",
                (unsigned long long)r.faces, (unsigned long long)r.free_surface,
                (unsigned long long)(r.faces - r.free_surface), r.least_dt,
                (unsigned long long)r.least_dt_element);
  return meta;
}

}  // namespace weaver::boundary_scan
