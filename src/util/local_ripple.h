// The octants a 2:1 face+edge balance creates inside a set of local
// leaves: those required to be resolved that lie strictly inside a leaf.
// Construct's subtree balance and balance's windows both ripple their
// leaves (their own and those of their insulation layer) through it.
//
// A leaf of level l asks for the octants of level l - 1 that it touches
// (its parent's face and edge neighbours on its own sides); an octant made
// by a split makes its siblings too, so its parent asks for all of its
// neighbours.  The requirements ripple from fine to coarse, one level at a
// time, through a map of the leaves, their ancestors (inner octants) and
// the octants created so far.  A neighbour whose nearest octant in the
// map, going up, is inner lies where no local leaf is: it is not created.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "schema/octant.h"
#include "util/octant_map.h"

namespace weaver {

class LocalRipple {
 public:
  // local: leaves in key order.  *created: the octants required strictly
  // inside a local leaf, in key order.  False (and *created incomplete)
  // once its map, asks and *created would take more than max_bytes.
  bool run(const std::vector<uint64_t>& local, std::vector<uint64_t>* created,
           size_t max_bytes = SIZE_MAX);
  // What its map and asks hold, and `created`.
  size_t bytes(const std::vector<uint64_t>& created) const;

 private:
  struct Ask {
    uint64_t parent;
    unsigned children;  // a bit for each child that asks (255: all)
    bool created;       // a created child asks (its grandparent may be a leaf)
  };

  void add_ask(int level, uint64_t parent, unsigned child_bit);
  bool ask_level(int level, std::vector<uint64_t>* created, size_t max_bytes);
  void consider(uint64_t nb, int level, std::vector<uint64_t>* created);

  OctantMap map_;
  uint64_t within_ = 0, within_end_ = 0;  // the leaf or created octant consider() last found
  std::array<std::vector<Ask>, kMaxLevel + 1> asks_;  // by the level of the children
  std::array<bool, kMaxLevel + 1> unsorted_{};        // created octants added to asks_
  std::vector<uint64_t> scratch_;                     // the radix sorts' other buffers
  std::vector<Ask> ask_scratch_;
};

}  // namespace weaver
