// The B+tree's concrete forward cursor.  It pins one leaf and remembers the
// root-to-leaf path, so moving to the next leaf climbs only as far as needed
// (no sibling links on disk).
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "storage/buffer_pool.h"
#include "storage/decoded_leaves.h"
#include "storage/page_format.h"
#include "storage/store.h"

namespace weaver {

class BTree;

// A root-to-leaf path: for each internal level, the page and the child taken.
struct TreePath {
  static constexpr int kMaxDepth = 48;  // far beyond any tree 2^32 pages can hold
  struct Entry {
    uint32_t page_no;
    uint32_t index;
  };
  Entry e[kMaxDepth];
  int depth = 0;
};

class BTreeCursor final : public Cursor {
 public:
  BTreeCursor() = default;
  BTreeCursor(BTreeCursor&&) = default;
  BTreeCursor& operator=(BTreeCursor&&) = default;

  bool valid() const override { return valid_; }
  uint64_t key() const override { return keys_[i_]; }
  const std::byte* payload() const override { return vals_ + size_t{payload_} * i_; }
  Status next() override {
    if (++i_ < n_) return Status::Ok();
    return next_leaf();
  }
  // The keys from the current record to the end of the leaf it holds (at
  // least one), valid until the cursor leaves that leaf.  REQUIRES: valid().
  const uint64_t* keys_in_leaf(uint32_t* count) const {
    *count = n_ - i_;
    return keys_ + i_;
  }
  // Moves on by k records, k at most what keys_in_leaf counts: to the next
  // leaf when k reaches the end of this one.  REQUIRES: valid().
  Status skip(uint32_t k) {
    i_ += k;
    if (i_ < n_) return Status::Ok();
    return next_leaf();
  }
  // Moves on, within the leaf it holds, to the first record with key > k,
  // if the leaf has one, setting *last to the record before it; false (and
  // no move) if the leaf ends at or before k.  A search in keys decoded
  // already: seeking from the tree would decode a whole packed leaf again.
  // REQUIRES: valid(), key() <= k.
  bool skip_in_leaf(uint64_t k, uint64_t* last) {
    if (keys_[n_ - 1] <= k) return false;
    i_ = static_cast<uint32_t>(std::upper_bound(keys_ + i_, keys_ + n_, k) - keys_);
    *last = keys_[i_ - 1];
    return true;
  }
  // Moves, either way within the leaf it holds, to the first record with
  // key >= k when the leaf's keys reach from k or below to k or above;
  // false (and no move) otherwise, or when not valid().
  bool seek_in_leaf(uint64_t k) {
    if (!valid_ || k < keys_[0] || keys_[n_ - 1] < k) return false;
    i_ = static_cast<uint32_t>(std::lower_bound(keys_, keys_ + n_, k) - keys_);
    return true;
  }
  // Keeps decoded packed leaves in `leaves` (shared with other cursors, of
  // this tree or of other handles of its table), and finds them there when
  // it comes back to them: a model region's scans read each leaf of the
  // model table about nine times over, and decoding it was a tenth of a
  // construct from a model database.  Only for a tree nobody writes while
  // the cursor lives; null keeps none.  `leaves` outlives the cursor.
  void keep_decoded(DecodedLeaves* leaves) { kept_ = leaves; }
  // The record before the current one in the leaf it holds: false at the
  // leaf's first record, or when not valid().
  bool before_in_leaf(uint64_t* key, const std::byte** payload) const {
    if (!valid_ || i_ == 0) return false;
    *key = keys_[i_ - 1];
    *payload = vals_ + size_t{payload_} * (i_ - 1);
    return true;
  }

 private:
  friend class BTree;
  Status next_leaf();
  // Positions on `leaf` at index i, moving on to later leaves if i is past its end.
  Status settle();
  Status load_leaf();
  // load_leaf from, or into, the kept leaves.
  Status load_kept();
  Status decode_leaf(uint64_t* keys, std::byte* vals);

  BTree* tree_ = nullptr;
  PageRef leaf_;
  TreePath path_;
  uint32_t i_ = 0;
  uint32_t n_ = 0;
  uint32_t payload_ = 0;
  const uint64_t* keys_ = nullptr;  // the leaf's keys and payloads (see load_leaf)
  const std::byte* vals_ = nullptr;
  std::vector<uint64_t> key_buf_;  // a packed leaf, decoded
  std::vector<std::byte> val_buf_;
  bool valid_ = false;
  bool keys_only_ = false;  // see BTree::seek_keys
  DecodedLeaves* kept_ = nullptr;
  std::shared_ptr<const DecodedLeaves::Leaf> kept_leaf_;  // the kept leaf keys_ points into
};

}  // namespace weaver
