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
  DomainMap(const DomainMap&) = delete;  // writers point to it
  DomainMap& operator=(const DomainMap&) = delete;

  // Adds the leaves of one stretch of key order to the map: leaf keys in
  // increasing order, then finish().  All the leaves are one stretch;
  // writers of stretches that meet at a key stretch_start gave write
  // different words of the map, so they may run on threads of their own.
  class Writer {
   public:
    explicit Writer(DomainMap* map) : map_(map) {}
    void add_leaf(uint64_t key);
    void finish() { close_cell(); }

   private:
    void close_cell();

    DomainMap* map_;
    uint64_t cell_ = 0;    // the cell the leaves finer than the map are filling
    uint64_t volume_ = 0;  // what they cover of it, in level-20 cells
    bool open_ = false;
  };

  // The first key of the run of 64 cells (one word of the map) that holds
  // the octant with this key: where two writers' stretches may meet.  0
  // when that is the map's start.
  uint64_t stretch_start(uint64_t key) const;

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
  int level_;
  std::vector<uint64_t> any_, full_;  // a bit a cell, cells in Morton order
};

}  // namespace weaver
