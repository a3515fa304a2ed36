// A forward walk of the octant table beside a nondecreasing stream of
// keys: for each key, the last leaf at or before it.  Where the stream is
// sparse it jumps ahead by a search instead of reading every leaf between,
// so a walk costs its keys, not the whole table.  The closure's domain
// probe and the windows' insulation layers both walk this way.
#pragma once

#include <cstdint>

#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

class ForwardFloor {
 public:
  Status open(BTree& leaves, uint64_t from = 0) {
    leaves_ = &leaves;
    has_last_ = false;
    return leaves.seek_keys(from, &cursor_);
  }

  // last() := the last leaf <= key; the cursor at the first leaf > key.
  // REQUIRES: key not below an earlier call's.
  Status advance_to(uint64_t key) {
    for (int steps = 0; cursor_.valid() && cursor_.key() <= key; ++steps) {
      if (steps == kWalk) return jump_to(key);
      last_ = cursor_.key();
      has_last_ = true;
      WEAVER_RETURN_IF_ERROR(cursor_.next());
    }
    return Status::Ok();
  }
  bool has_last() const { return has_last_; }
  uint64_t last() const { return last_; }  // REQUIRES: has_last()

  // The first leaf after last(), if any.
  bool has_next() const { return cursor_.valid(); }
  uint64_t next_key() const { return cursor_.key(); }  // REQUIRES: has_next()

 private:
  // Leaves read one by one before jumping.  A jump within the leaf the
  // cursor holds is a search of keys decoded already; one past it, two
  // searches from the root, decoding the new leaf whole.
  static constexpr int kWalk = 64;

  Status jump_to(uint64_t key) {
    if (cursor_.skip_in_leaf(key, &last_)) {
      has_last_ = true;
      return Status::Ok();
    }
    uint64_t floor = 0;
    bool hit = false;
    WEAVER_RETURN_IF_ERROR(leaves_->floor(key, &floor, nullptr, &hit));
    if (hit) {
      last_ = floor;
      has_last_ = true;
    }
    return leaves_->seek_keys(key + 1, &cursor_);
  }

  BTree* leaves_ = nullptr;
  BTreeCursor cursor_;
  uint64_t last_ = 0;
  bool has_last_ = false;
};

}  // namespace weaver
