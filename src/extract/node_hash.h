// An open-addressing hash from node key to an 8-bit direction mask: which of
// the 8 cells around the node hold an element that has the node as a corner.
// This is the paper's per-bucket hash table of nodal pixels: the reader's
// for the corners it spills, and the workers' where a bucket's keys span too
// many bits for NodeWords (node_words.h), which they use everywhere else.
#pragma once

#include <bit>
#include <cstdint>
#include <vector>

#include "util/key_set.h"

namespace weaver {

class NodeHash {
 public:
  // Empties the table, keeping room for `expected` keys without growing.
  // A table of the same size is emptied slot by used slot: a bucket fills a
  // few of the slots sized for its worst case, and clearing them all was 4%
  // of an extract.
  void reset(size_t expected) {
    size_t cap = 64;
    while (cap < 2 * expected) cap <<= 1;
    if (cap == slots_.size()) {
      for (uint32_t s : used_) slots_[s] = kEmpty, masks_[s] = 0;
    } else {
      slots_.assign(cap, kEmpty);
      masks_.assign(cap, 0);
    }
    used_.clear();
    limit_ = cap / 2;
    shift_ = 64 - static_cast<int>(std::bit_width(cap) - 1);
  }

  // ORs bits into the key's mask, inserting the key if new.
  void add(uint64_t key, uint8_t bits) {
    if (used_.size() >= limit_) grow();
    const size_t s = find_slot(key);
    if (slots_[s] == kEmpty) {
      slots_[s] = key;
      used_.push_back(static_cast<uint32_t>(s));
    }
    masks_[s] |= bits;
  }

  size_t size() const { return used_.size(); }
  // The keys, in insertion order, and their masks.
  uint64_t key_at(size_t i) const { return slots_[used_[i]]; }
  uint8_t mask_at(size_t i) const { return masks_[used_[i]]; }

 private:
  // Node keys use 63 bits, so an all-ones slot can mark "empty".
  static constexpr uint64_t kEmpty = ~uint64_t{0};

  size_t find_slot(uint64_t key) const { return probe_slot(slots_, shift_, key, kEmpty); }

  void grow() {
    std::vector<uint64_t> keys;
    std::vector<uint8_t> masks;
    for (size_t i = 0; i < used_.size(); ++i) {
      keys.push_back(key_at(i));
      masks.push_back(mask_at(i));
    }
    reset(2 * slots_.size());
    for (size_t i = 0; i < keys.size(); ++i) add(keys[i], masks[i]);
  }

  std::vector<uint64_t> slots_;
  std::vector<uint8_t> masks_;
  std::vector<uint32_t> used_;
  size_t limit_ = 0;  // at most half the slots are used: past it, grow
  int shift_ = 58;
};

}  // namespace weaver
