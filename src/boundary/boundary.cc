#include "boundary/boundary.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <functional>
#include <memory>
#include <vector>

#include "db/boundary_table.h"
#include "db/leaf_reader.h"
#include "db/octant_table.h"
#include "db/table_files.h"
#include "mesh/face_neighbors.h"
#include "mesh/mesh_reader.h"
#include "model/ground_model.h"
#include "util/parallel.h"

namespace weaver {
namespace {

// The box the leaves span (ticks), and whether their volumes fill it.
struct Span {
  std::array<uint32_t, 3> lo{UINT32_MAX, UINT32_MAX, UINT32_MAX}, hi{};  // hi: the far side
  unsigned __int128 volume = 0;
  bool filled = true;

  void add(const Octant& o) {
    const uint32_t e = octant_edge(o), c[3] = {o.x, o.y, o.z};
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], c[a]);
      hi[a] = std::max(hi[a], c[a] + e);
    }
    volume += static_cast<unsigned __int128>(uint64_t{e} * e) * e;
  }
  void add(const Span& s) {
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], s.lo[a]), hi[a] = std::max(hi[a], s.hi[a]);
    volume += s.volume;
  }
  // Once every leaf is in: whether they fill the box.
  void settle() {
    if (volume == 0) return;
    unsigned __int128 box = 1;
    for (int a = 0; a < 3; ++a) box *= hi[a] - lo[a];
    filled = volume == box;
  }
};

// The leaves with ids [first, stop) of the table: their span (not settled)
// and, with vp, their least edge / vp and its element.
struct Share {
  Span span;
  double least_dt = HUGE_VAL;
  uint64_t least_dt_element = 0;
};

// The leaves with ids [first, stop) in key order: fn(id, leaf), and with vp
// their least edge / vp (seconds) and its element into *least, *element.
template <class Fn>
Status walk_leaves(BTree& octants, uint64_t first, uint64_t stop, const Field* vp, double* least,
                   uint64_t* element, Fn fn) {
  if (first >= stop) return Status::Ok();
  uint64_t key = 0;
  WEAVER_RETURN_IF_ERROR(octants.select(first, &key, nullptr));
  LeafReader r;
  WEAVER_RETURN_IF_ERROR(r.open(octants, key, vp != nullptr));
  Units units;
  units_from_metadata(octants.options().metadata, &units);
  for (uint64_t id = first; id < stop && r.valid(); ++id) {
    const Octant leaf = octant_from_key(r.key());
    if (vp != nullptr) {
      const double dt =
          octant_edge(leaf) * units.tick_m / RecordSchema::get_double(r.payload(), *vp);
      if (dt < *least) *least = dt, *element = id;
    }
    WEAVER_RETURN_IF_ERROR(fn(id, leaf));
    WEAVER_RETURN_IF_ERROR(r.next());
  }
  return Status::Ok();
}

Status share_of(BTree& octants, uint64_t first, uint64_t stop, const Field* vp, Share* s) {
  return walk_leaves(octants, first, stop, vp, &s->least_dt, &s->least_dt_element,
                     [s](uint64_t, const Octant& leaf) {
                       s->span.add(leaf);
                       return Status::Ok();
                     });
}

// The ground a carved mesh was built under, read again from the octant
// table's metadata; none (flat, or the surface file gone) leaves every
// element to the table's answer.
struct GroundCheck {
  std::unique_ptr<Surface> surface;
  Ground ground;
  double tick_m = 0;
  bool ready = false;

  void load(const std::string& metadata, const Units& units, MemoryBudget memory) {
    if (!ground_of_metadata(metadata, memory.bytes(), &surface, &ground).ok()) return;
    tick_m = units.tick_m;
    ready = true;
  }
  // Whether every leaf around o (within its edge) lies wholly below ground.
  bool buried(const Octant& o) const {
    if (!ready) return false;
    const double e = octant_edge(o) * tick_m;
    const double lo[3] = {o.x * tick_m - e, o.y * tick_m - e, o.z * tick_m - e};
    const double hi[3] = {lo[0] + 3 * e, lo[1] + 3 * e, lo[2] + 3 * e};
    return side_of_ground(ground, lo, hi) == GroundSide::kSolid;
  }
};

// The face's two in-plane axes, in x, y, z order.
void face_axes(int face, int* u, int* v) {
  const int axis = face / 2;
  *u = axis == 0 ? 1 : 0;
  *v = axis == 2 ? 1 : 2;
}

// Where the records go, in key order: the new table, or verify's comparison
// with the stored one.
using BoundarySink = std::function<Status(uint64_t key, uint8_t kind)>;

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
    if (!ground.buried(o)) {
      ++r_->asked;
      neighbours_.clear();
      WEAVER_RETURN_IF_ERROR(finder->find(o, &neighbours_));
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
        if (on_side[f] || whole[f]) continue;
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

// Elements done by every thread, reported by one.
struct Tally {
  std::atomic<uint64_t> done{0};
  uint64_t total = 0;
  ProgressFn report;  // called by the thread of range 0 alone
};

// The ground a carved mesh was built under, where the leaves leave holes.
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

// Adds a later range's result to *r (ranges in id order: the first least
// edge / vp kept on a tie, as one scan finds it).
void add_result(const BoundaryResult& later, BoundaryResult* r) {
  r->elements += later.elements, r->faces += later.faces, r->quarters += later.quarters;
  r->free_surface += later.free_surface, r->asked += later.asked;
  if (later.elements > 0 && later.least_dt > 0 &&
      (r->least_dt == 0 || later.least_dt < r->least_dt))
    r->least_dt = later.least_dt, r->least_dt_element = later.least_dt_element;
}

// The boundary records of the whole octant table, into `out` in key order,
// on one thread a handle of the table (tables[0] the caller's): the ids cut
// into equal ranges, range 0 derived straight into `out`, the others at the
// same time into memory, up to cap records each, then handed on in turn
// (the rest of a range whose worker stopped at its cap derived then).
Status derive_boundary(const std::vector<BTree*>& tables, const BoundarySink& out,
                       const BoundaryOptions& o, MemoryBudget surface, uint64_t cap,
                       BoundaryResult* r) {
  BTree& octants = *tables[0];
  const int t = int(tables.size());
  const uint64_t n = octants.size();
  const auto cut = [&](int i) { return n * uint64_t(i) / uint64_t(t); };
  Span span;
  if (o.known_filled_box) {
    span.lo = o.box_lo, span.hi = o.box_hi, span.filled = true;
  } else {
    std::vector<Share> shares(tables.size());
    WEAVER_RETURN_IF_ERROR(run_shares(
        t, [&](int i) { return share_of(*tables[i], cut(i), cut(i + 1), nullptr, &shares[i]); }));
    for (const Share& s : shares) span.add(s.span);
    span.settle();
  }
  GroundCheck ground;  // read-only once loaded: the threads share it
  load_ground(octants, span, surface, &ground);
  const Field* vp = o.known_least_dt > 0 ? nullptr : octants.options().schema.find("vp");
  Tally tally;
  tally.total = n, tally.report = o.progress;
  struct Range {
    std::vector<std::pair<uint64_t, uint8_t>> records;
    uint64_t reached = 0;
    BoundaryResult r;
  };
  std::vector<Range> ranges(tables.size());
  WEAVER_RETURN_IF_ERROR(run_shares(t, [&](int i) {
    Range& g = ranges[size_t(i)];
    if (i == 0) {
      return derive_records(octants, out, span, ground, 0, cut(1), vp, &tally, true, nullptr,
                            &g.reached, &g.r);
    }
    const BoundarySink keep = [&g](uint64_t key, uint8_t kind) {
      g.records.emplace_back(key, kind);
      return Status::Ok();
    };
    return derive_records(
        *tables[size_t(i)], keep, span, ground, cut(i), cut(i + 1), vp, &tally, false,
        [&g, cap] { return g.records.size() >= cap; }, &g.reached, &g.r);
  }));
  *r = ranges[0].r;
  for (int i = 1; i < t; ++i) {
    Range& g = ranges[size_t(i)];
    for (const auto& [key, kind] : g.records) WEAVER_RETURN_IF_ERROR(out(key, kind));
    add_result(g.r, r);
    std::vector<std::pair<uint64_t, uint8_t>>().swap(g.records);
    if (g.reached < cut(i + 1)) {  // stopped at its cap: the rest here
      BoundaryResult rest;
      uint64_t reached = 0;
      WEAVER_RETURN_IF_ERROR(derive_records(octants, out, span, ground, g.reached, cut(i + 1), vp,
                                            &tally, true, nullptr, &reached, &rest));
      add_result(rest, r);
    }
  }
  r->filled = span.filled;
  if (o.known_least_dt > 0)
    r->least_dt = o.known_least_dt, r->least_dt_element = o.known_least_dt_element;
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

Status write_boundary(const std::vector<BTree*>& octants, BTree& out, const BoundaryOptions& o,
                      MemoryBudget surface, uint64_t cap, BoundaryResult* r) {
  const BoundarySink append = [&out](uint64_t key, uint8_t kind) {
    return out.append(key, reinterpret_cast<const std::byte*>(&kind));
  };
  WEAVER_RETURN_IF_ERROR(derive_boundary(octants, append, o, surface, cap, r));
  out.set_metadata(boundary_metadata(*r));
  return Status::Ok();
}

}  // namespace

Status build_boundary(const std::string& db_dir, const BoundaryOptions& o, BoundaryResult* r) {
  *r = BoundaryResult{};
  MemoryPlan plan(o.memory);
  // Both scans and the lookups read the octant table (a handle a thread);
  // the writer appends.
  const int threads = std::max(1, o.threads);
  const uint64_t octant_pool = plan.take("octant table pools", 1, 4) / uint64_t(threads);
  const uint64_t out_pool = plan.take("boundary table pool", 1, 8, 8ull << 20);
  // A carved mesh's surface, read again (model/surface.h).
  const MemoryBudget surface = plan.take_budget("surface", 1, 4);
  // The records the threads past the first hold until their turn.
  uint64_t cap = threads > 1 ? plan.take("records held by the other threads", 1, 4) /
                                   (sizeof(std::pair<uint64_t, uint8_t>) * (threads - 1))
                             : 0;
  if (o.held_records > 0) cap = std::min(cap, o.held_records);
  std::unique_ptr<Database> own;
  Database* db = o.writer;
  if (db == nullptr) {
    WEAVER_RETURN_IF_ERROR(Database::open(db_dir, Database::Mode::kWrite, false, &own));
    db = own.get();
  }
  if (!db->has_table(kOctantTable)) return Status::NotFound(db_dir + ": no octant table");
  std::vector<std::unique_ptr<BTree>> handles(static_cast<size_t>(threads));
  std::vector<BTree*> octants;
  for (auto& h : handles) {
    WEAVER_RETURN_IF_ERROR(db->open_table(kOctantTable, octant_pool, &h));
    octants.push_back(h.get());
  }
  std::unique_ptr<BTree> table;
  std::string file;
  WEAVER_RETURN_IF_ERROR(
      db->create_table(kBoundaryTable, boundary_table_options(o.packed), out_pool, &table, &file));
  const Status st = write_boundary(octants, *table, o, surface, cap, r);
  WEAVER_RETURN_IF_ERROR(db->publish(kBoundaryTable, file, table, st));
  r->table_bytes = table->file_bytes();
  return Status::Ok();
}

namespace {

// A rank's share as text for the others ("" when it failed), and back.
std::string share_text(const Share& s) {
  char buf[320];
  std::snprintf(buf, sizeof buf, "%u %u %u %u %u %u %llu %llu %a %llu", s.span.lo[0], s.span.lo[1],
                s.span.lo[2], s.span.hi[0], s.span.hi[1], s.span.hi[2],
                (unsigned long long)(s.span.volume >> 64), (unsigned long long)s.span.volume,
                s.least_dt, (unsigned long long)s.least_dt_element);
  return buf;
}

bool parse_share(const std::string& text, Share* s) {
  unsigned long long hi = 0, lo = 0, element = 0;
  char dt[64] = {};
  if (std::sscanf(text.c_str(), "%u %u %u %u %u %u %llu %llu %63s %llu", &s->span.lo[0],
                  &s->span.lo[1], &s->span.lo[2], &s->span.hi[0], &s->span.hi[1], &s->span.hi[2],
                  &hi, &lo, dt, &element) != 10) {
    return false;
  }
  s->span.volume = (static_cast<unsigned __int128>(hi) << 64) | lo;
  s->least_dt = std::strtod(dt, nullptr);
  s->least_dt_element = element;
  return true;
}

// Every rank's share, combined as one scan of the whole table finds them
// (the least edge / vp of the first rank that has it: the least id).
// False when a rank failed (sent "").
bool combine_shares(const std::vector<std::string>& texts, Share* all) {
  *all = Share{};
  for (const std::string& text : texts) {
    Share s;
    if (!parse_share(text, &s)) return false;
    all->span.add(s.span);
    if (s.least_dt < all->least_dt)
      all->least_dt = s.least_dt, all->least_dt_element = s.least_dt_element;
  }
  all->span.settle();
  return true;
}

}  // namespace

Status boundary_shard(const std::string& db_dir, const BoundaryOptions& o, int rank, int ranks,
                      const std::string& file, const RankAllGather& all_gather, BoundaryResult* r,
                      ShardEntry* entry) {
  *r = BoundaryResult{};
  *entry = ShardEntry{file};
  MemoryPlan plan(o.memory);
  const uint64_t octant_pool = plan.take("octant table pool", 1, 4);
  const uint64_t out_pool = plan.take("boundary table pool", 1, 8, 8ull << 20);
  const MemoryBudget surface = plan.take_budget("surface", 1, 2);
  // Up to each exchange, an error still takes part in it (sending "").
  std::unique_ptr<Database> db;
  std::unique_ptr<BTree> octants;
  Status st = Database::open(db_dir, Database::Mode::kRead, false, &db);
  if (st.ok() && !o.staged_octants.empty()) {
    st = db->stage_shards(kOctantTable, o.staged_octants);
  }
  if (st.ok() && !db->has_table(kOctantTable)) st = Status::NotFound(db_dir + ": no octant table");
  if (st.ok()) st = db->open_table(kOctantTable, octant_pool, &octants);
  const uint64_t n = st.ok() ? octants->size() : 0;
  const uint64_t first = n * uint64_t(rank) / uint64_t(ranks);
  const uint64_t stop = n * uint64_t(rank + 1) / uint64_t(ranks);
  const Field* vp = st.ok() ? octants->options().schema.find("vp") : nullptr;
  Share mine, all;
  if (st.ok()) st = share_of(*octants, first, stop, vp, &mine);
  std::vector<std::string> texts;
  WEAVER_RETURN_IF_ERROR(all_gather(st.ok() ? share_text(mine) : "", &texts));
  WEAVER_RETURN_IF_ERROR(st);
  if (!combine_shares(texts, &all)) return Status::Ok();  // another rank failed: it says why
  // This rank's records, into a shard file of the table.
  std::unique_ptr<BTree> table;
  st = create_shard_table(db_dir, file, boundary_table_options(o.packed), out_pool, &table);
  const BoundarySink append = [&table](uint64_t key, uint8_t kind) {
    return table->append(key, reinterpret_cast<const std::byte*>(&kind));
  };
  if (st.ok()) {
    GroundCheck ground;
    load_ground(*octants, all.span, surface, &ground);
    Tally tally;
    tally.total = stop - first, tally.report = o.progress;
    uint64_t reached = 0;
    st = derive_records(*octants, append, all.span, ground, first, stop, nullptr, &tally, true,
                        nullptr, &reached, r);
  }
  // The counts of every rank, for the metadata every shard carries.
  char counts[96];
  std::snprintf(counts, sizeof counts, "%llu %llu", (unsigned long long)r->faces,
                (unsigned long long)r->free_surface);
  const Status gathered = all_gather(st.ok() ? counts : "", &texts);
  BoundaryResult total = *r;
  total.faces = total.free_surface = 0;
  std::vector<bool> writes;
  bool peer_failed = false;
  for (const std::string& text : texts) {
    unsigned long long faces = 0, free_surface = 0;
    if (std::sscanf(text.c_str(), "%llu %llu", &faces, &free_surface) != 2) {
      peer_failed = true;
      break;
    }
    total.faces += faces, total.free_surface += free_surface;
    writes.push_back(faces > 0);
  }
  if (st.ok()) st = gathered;
  total.least_dt = vp != nullptr && n > 0 ? all.least_dt : 0;
  total.least_dt_element = vp != nullptr ? all.least_dt_element : 0;
  r->least_dt = total.least_dt, r->least_dt_element = total.least_dt_element;
  if (table == nullptr) return st;
  // A failed rank says why; the others only drop their files.
  const bool drop = st.ok() && peer_failed;
  if (st.ok() && !drop) table->set_metadata(boundary_metadata(total));
  const ShardPlace place = st.ok() && !drop ? shard_place_among(writes, rank) : ShardPlace{};
  const Status finished = finish_shard(db_dir, table, drop ? Status::Internal("dropped") : st,
                                       place, entry, &r->table_bytes);
  return drop ? Status::Ok() : finished;
}

Status check_boundary(BTree& octants, BTree& stored, MemoryBudget surface, size_t max_problems,
                      std::vector<std::string>* problems) {
  std::unique_ptr<Cursor> c;
  WEAVER_RETURN_IF_ERROR(stored.seek(0, &c));
  auto where = [](uint64_t key) {
    return "element " + std::to_string(key >> 6) + " face " + std::to_string(key >> 3 & 7) +
           " part " + std::to_string(key & 7);
  };
  auto add = [&](std::string p) {
    if (problems->size() < max_problems) problems->push_back("table boundary: " + std::move(p));
  };
  // Both sides come in key order: walk them together.
  const BoundarySink compare = [&](uint64_t key, uint8_t kind) -> Status {
    while (c->valid() && c->key() < key) {
      add(where(c->key()) + " is stored, but is not a boundary");
      WEAVER_RETURN_IF_ERROR(c->next());
    }
    if (!c->valid() || c->key() != key) {
      add(where(key) + " is a boundary, but is not stored");
      return Status::Ok();
    }
    const auto got = static_cast<uint8_t>(*c->payload());
    if (got != kind) {
      add(where(key) + " is stored as kind " + std::to_string(got) + ", not " +
          std::to_string(kind));
    }
    return c->next();
  };
  BoundaryOptions o;
  o.known_least_dt = 1;  // the time step is not the table's: keys alone
  BoundaryResult r;
  WEAVER_RETURN_IF_ERROR(derive_boundary({&octants}, compare, o, surface, 0, &r));
  while (c->valid()) {
    add(where(c->key()) + " is stored, but is not a boundary");
    WEAVER_RETURN_IF_ERROR(c->next());
  }
  return Status::Ok();
}

}  // namespace weaver
