// The octants a 2:1 face+edge balance creates inside a set of local
// leaves: those required to be resolved that lie strictly inside a leaf.
// Construct's subtree balance and balance's windows both ripple their
// leaves (their own and those of their insulation layer) through it.
//
// A leaf of level l asks for the octants of level l - 1 that it touches
// (its parent's face and edge neighbours on its own sides); an octant made
// by a split makes its siblings too, so its parent asks for all of its
// neighbours.  The requirements ripple from fine to coarse, one level at a
// time.  A level's asks give its candidates (octants one level coarser);
// sorted, each is looked up among the leaves that could hold it, in the
// same order, and made if it lies strictly inside one.  A candidate where
// no local leaf is is not made.
//
// Everything is sorted and merged, nothing hashed: the lookups walk the
// leaves forwards, so a window of millions of leaves does not wait on
// memory at every candidate, as a map of them did once it outgrew the
// cache (half of a 10M-leaf balance).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "schema/octant.h"
#include "util/recent_keys.h"

namespace weaver {

class LocalRipple {
 public:
  // threads: how many share a level's asks, where there are many (one
  // window of a whole table); subtrees and windows, already one a thread,
  // take one.
  explicit LocalRipple(int threads = 1) : lanes_(threads < 2 ? 1 : 2) {}

  // local: leaves in key order.  *created: the octants required strictly
  // inside a local leaf, in key order.  False (and *created incomplete)
  // once what it holds and *created would take more than max_bytes.
  bool run(const std::vector<uint64_t>& local, std::vector<uint64_t>* created,
           size_t max_bytes = SIZE_MAX);
  // What it holds, and `created`.
  size_t bytes(const std::vector<uint64_t>& created) const;

 private:
  struct Ask {
    uint64_t parent;
    uint32_t children;  // a bit for each child that asks (255: all)
    bool created;       // a created child asks (its grandparent may be a leaf)
  };
  // One thread's share of a level's asks: their candidates, settled a
  // chunk at a time into the octants they create.
  struct Lane {
    std::vector<uint64_t> candidates, scratch, made;
    // The candidates seen last: neighbouring asks ask about the same
    // octants (four times over, in random refinement), and a repeat found
    // here never reaches the sort.
    RecentKeys<12> recent;
    void take(const Ask* begin, const Ask* end, int level, const std::vector<uint64_t>& holders);
    void settle(int level, const std::vector<uint64_t>& holders);
    size_t bytes() const;
  };

  void gather(const std::vector<uint64_t>& local, int coarsest, int finest);
  void merge_asks(int level, const std::vector<uint64_t>& created);
  bool ask_level(int level, std::vector<uint64_t>* created, size_t max_bytes);
  void merge_runs(std::vector<uint64_t>* created);
  void merge_pairs(std::vector<uint64_t>* created);

  const size_t lanes_;
  std::array<std::vector<Ask>, kMaxLevel + 1> leaf_asks_;  // by the level of the children
  std::vector<uint64_t> holders_;  // the leaves coarse enough to hold a created octant
  std::vector<Ask> asks_;          // one level's, the leaves' and the created octants'
  size_t made_from_ = 0;           // where the last level's created octants start
  std::vector<size_t> runs_;       // where each level's created octants start, and the end
  std::array<Lane, 2> lane_;
  std::vector<uint64_t> scratch_;
};

}  // namespace weaver
