// The boundary table's scan (boundary.h), shared by its three users:
// build_boundary (on threads), boundary_shard (a rank of weaver-mpi) and
// check_boundary (weaver verify).  Internal to src/boundary.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <functional>
#include <memory>
#include <string>

#include "boundary/boundary.h"
#include "db/leaf_reader.h"
#include "db/octant_table.h"
#include "model/ground_model.h"
#include "storage/btree.h"
#include "util/leaf_span.h"

namespace weaver::boundary_scan {

// The box the leaves span (ticks), and whether their volumes fill it.
using Span = LeafSpan;

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

// The leaves [first, stop) of the table: their span (not settled) and,
// with vp, their least edge / vp and its element.
Status share_of(BTree& octants, uint64_t first, uint64_t stop, const Field* vp, Share* s);

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
  // The faces of o (bit f for face f) across which something may be open:
  // those whose box of o's size across the face is not wholly below the
  // ground (leaves that meet such a box in volume are never air).  Every
  // face where there is no ground to go by.
  unsigned open_faces(const Octant& o) const {
    if (!ready) return 0x3F;
    const double e = octant_edge(o) * tick_m;
    const double at[3] = {o.x * tick_m, o.y * tick_m, o.z * tick_m};
    unsigned open = 0;
    for (int f = 0; f < 6; ++f) {
      double lo[3] = {at[0], at[1], at[2]};
      lo[f / 2] += (f & 1) ? e : -e;
      const double hi[3] = {lo[0] + e, lo[1] + e, lo[2] + e};
      if (side_of_ground(ground, lo, hi) != GroundSide::kSolid) open |= 1u << f;
    }
    return open;
  }
};

// Where the records go, in key order: the new table, or verify's comparison
// with the stored one.
using BoundarySink = std::function<Status(uint64_t key, uint8_t kind)>;

// Elements done by every thread, reported by one.
struct Tally {
  std::atomic<uint64_t> done{0};
  uint64_t total = 0;
  ProgressFn report;  // called by the thread of range 0 alone
};

// The ground a carved mesh was built under, where the leaves leave holes.
void load_ground(BTree& octants, const Span& span, MemoryBudget surface, GroundCheck* ground);

// The boundary records of the elements with ids [first, stop) of the
// octant table, into `out` in key order, the leaves spanning `span`
// (settled); with vp, their least edge / vp is found on the way.  When
// full() says so after an element, stops there; *reached: the first id
// not done.
Status derive_records(BTree& octants, const BoundarySink& out, const Span& span,
                      const GroundCheck& ground, uint64_t first, uint64_t stop, const Field* vp,
                      Tally* tally, bool reports, const std::function<bool()>& full,
                      uint64_t* reached, BoundaryResult* r);

TableOptions boundary_table_options(bool packed);
// The boundary table's metadata: its counts and least edge / vp.
std::string boundary_metadata(const BoundaryResult& r);

}  // namespace weaver::boundary_scan
