// Floor lookups answered from one decoded table leaf at a time.  A batch of
// keys in ascending order (points sorted by Morton code) mostly lands in the
// leaf the key before it landed in: one descent and one decode serve every
// key of a leaf's span, where separate floor() calls would pay a descent and
// a packed-leaf decode each.  Keys in any order are still answered correctly.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

class LeafWindow {
 public:
  // With payloads, floor() also hands out the payload of the key it finds.
  LeafWindow(BTree& table, bool payloads) : t_(table), payloads_(payloads) {}

  struct Floor {
    bool found = false;  // false: no key <= the one asked
    uint64_t key = 0;
    uint64_t rank = 0;                   // the number of keys < key
    const std::byte* payload = nullptr;  // valid until the next call
  };
  // The largest key <= key.
  Status floor(uint64_t key, Floor* out);
  // Sparse: answer each key by its own floor and rank descents, without
  // decoding whole leaves.  For a few keys (one question) that is cheaper;
  // for a batch that lands many keys in each leaf, the decoded leaf is.
  void set_sparse(bool sparse) { sparse_ = sparse; }

 private:
  Status sparse_floor(uint64_t key, Floor* out);
  Status load(uint64_t key);

  BTree& t_;
  bool payloads_;
  bool sparse_ = false;
  std::vector<uint64_t> keys_;  // the decoded leaf
  std::vector<std::byte> vals_;
  uint64_t first_rank_ = 0;
  std::vector<std::byte> before_;  // payload of the key before the leaf, when asked
};

}  // namespace weaver
