// A coarse picture of the domain (the union of the leaves) for balance's
// level passes, built in their first scan of the leaves.
//
// Each level pass keeps only the candidates that overlap the domain.  Asking
// the leaf table costs a walk or a search per candidate, and on a mesh with
// 100M leaves that was a third of balance, all of it on one thread.  Nearly
// every candidate lies in a cell of some coarse level L that is either empty
// or covered by leaves, so two bits a cell (some leaf overlaps it; leaves
// cover it) answer it; only cells the domain's boundary cuts finer than L
// are left to the table.
#pragma once

#include <cstdint>
#include <vector>

namespace weaver {

class DomainMap {
 public:
  enum class Answer { kNo, kYes, kAskTheLeaves };

  // The finest level whose map fits in `bytes` (2 bits a cell), at most
  // finest_leaf_level (finer cells would tell no more).
  static int level_for(uint64_t bytes, int finest_leaf_level);

  explicit DomainMap(int level);

  // Leaf keys, in increasing order, then finish().
  void add_leaf(uint64_t key);
  void finish();

  // Whether the octant with this key overlaps some leaf (shares volume
  // with it): kAskTheLeaves only for an octant finer than the map, inside
  // a cell the leaves cover in part.
  Answer overlaps(uint64_t key) const;

  // Whether the map knows the octant to lie wholly in the domain: it is in
  // a covered cell, or (a little coarser than the map) all its cells are
  // covered.  False says nothing.
  bool covers(uint64_t key) const;

  int level() const { return level_; }

 private:
  void close_cell();

  int level_;
  std::vector<uint64_t> any_, full_;  // a bit a cell, cells in Morton order
  uint64_t cell_ = 0;                 // the cell the leaves finer than the map are filling
  uint64_t volume_ = 0;               // what they cover of it, in level-20 cells
  bool open_ = false;
};

}  // namespace weaver
