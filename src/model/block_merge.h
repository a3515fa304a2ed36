// The merge of MaterialMerger (model/material_merge.h) done ahead of it, in
// memory, over one block: an aligned cube of 2^levels input octants a side
// whose values come all at once (a grid's block of points).  Sibling sets
// are merged bottom-up, level by level, with the merger's own rule, and
// only what is left goes to the merger, in key order: a uniform block costs
// it one add, not 8^levels.  The merger's output is the same as if every
// input octant had been added one by one.
#pragma once

#include <cstdint>
#include <vector>

#include "model/material_merge.h"
#include "schema/octant.h"
#include "schema/status.h"

namespace weaver {

class BlockMerger {
 public:
  // REQUIRES: 1 <= levels <= 7 (a block of at most 2M octants).
  explicit BlockMerger(int levels);

  int levels() const { return levels_; }
  uint32_t side() const { return uint32_t{1} << levels_; }
  // The input octants, by their Morton order inside the block (x fastest
  // in each group of eight): values[m] when present[m] is not 0.  Fill
  // both, then merge_into.
  std::vector<ModelValues>& values() { return values_; }
  std::vector<uint8_t>& present() { return present_; }

  // Merges the block whose root is `block` (its input octants of level
  // block.level + levels) and adds what is left to the merger.
  Status merge_into(const Octant& block, MaterialMerger& merger);

 private:
  Status emit(const Octant& o, int depth, uint64_t index, MaterialMerger& merger) const;

  int levels_;
  std::vector<ModelValues> values_;
  std::vector<uint8_t> present_;
  // By depth below the block's root (0 .. levels - 1): whether the node
  // merged into one octant, and its entry when it did.
  std::vector<std::vector<uint8_t>> whole_;
  std::vector<std::vector<MaterialMerger::Entry>> nodes_;
};

}  // namespace weaver
