// The query layer over an octant table: point location (the aggregate hit)
// and box range queries.
#pragma once

#include <cstdint>
#include <functional>

#include "schema/octant.h"
#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

struct LocateResult {
  bool inside = false;  // false: the point is in the root but no leaf holds it
  Octant leaf;
  uint64_t element_id = 0;  // the leaf's rank in key order
};

// The leaf that contains tick point p.  InvalidArgument if p is not a pixel
// (each axis must be < 2^20).
Status locate(BTree& octants, Coord p, LocateResult* out);

// A box of tick points, bounds included: lo <= p <= hi on every axis.
struct TickBox {
  Coord lo, hi;
};

// Counts the leaves that hold at least one point of the box, and calls
// on_leaf (if set) for each, in key order.  A leaf [c, c + edge) holds the
// points c <= p < c + edge.  Costs O(boundary octants x log n), not O(leaves):
// subtrees wholly inside the box are counted by rank.
// InvalidArgument if lo > hi on some axis or hi lies beyond the root.
Status range_query(BTree& octants, const TickBox& box, uint64_t* count,
                   const std::function<void(const Octant&, uint64_t id)>& on_leaf);

// One page of range_query's leaves: those with id >= from, in key order, at
// most limit of them, each given to on_leaf.  *next: the id of the first
// leaf of the box past the page (UINT64_MAX when the page ends the box).
// Skips the subtrees before `from` by rank, so a page costs what it lists
// plus O(boundary octants x log n), wherever it starts.
Status range_page(BTree& octants, const TickBox& box, uint64_t from, uint64_t limit,
                  const std::function<void(const Octant&, uint64_t id)>& on_leaf, uint64_t* next);

// The leaves of the box as runs of consecutive ids [first, end), in
// increasing order: what an export of the box reads instead of the mesh.
Status range_runs(BTree& octants, const TickBox& box,
                  const std::function<Status(uint64_t first, uint64_t end)>& on_run);

}  // namespace weaver
