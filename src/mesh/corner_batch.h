// The node ids of the corners of many elements at once.  Looking each corner
// up in the node table costs a descent and the decoding of part of a packed
// leaf: 8 of them an element.  For a batch of consecutive elements the
// corners fall into a few leaves: sort the batch's (corner key, slot) pairs
// by key, then walk them once, decoding each leaf they touch once, and hand
// each slot its key's rank.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "schema/octant.h"
#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

class CornerBatch {
 public:
  // ids[i] = the node ids of the corners of elements[i].  Corruption naming
  // the node when a corner is missing from the node table.
  Status resolve(BTree& nodes, const std::vector<Octant>& elements,
                 std::vector<std::array<uint64_t, 8>>* ids);

 private:
  struct KeySlot {
    uint64_t key;
    uint64_t slot;  // element * 8 + corner
  };
  std::vector<KeySlot> pairs_, scratch_;
  std::vector<uint64_t> leaf_;  // the keys of the leaf last decoded
  uint64_t leaf_rank_ = 0;      // the rank of its first key
};

}  // namespace weaver
