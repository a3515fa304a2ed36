// An open-addressing set of 64-bit keys, sized once for a known number of
// keys: 8 bytes a slot, at most half the slots used.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <vector>

namespace weaver {

// Linear probing from the key's Fibonacci hash (top bits, `shift` = 64 -
// log2 of the slot count): the slot holding `key`, or the empty slot where
// it would go.
inline size_t probe_slot(const std::vector<uint64_t>& slots, int shift, uint64_t key,
                         uint64_t empty) {
  size_t s = (key * 0x9E3779B97F4A7C15ULL) >> shift;
  while (slots[s] != empty && slots[s] != key) s = (s + 1) & (slots.size() - 1);
  return s;
}

class KeySet {
 public:
  // The slot count for `keys` keys: the least power of two >= 2 * keys.
  static size_t slots_for(size_t keys) { return std::bit_ceil(std::max<size_t>(64, 2 * keys)); }

  // Empties the set and makes room for `keys` keys; adding more is a bug.
  void reset(size_t keys) {
    slots_.assign(slots_for(keys), kEmpty);
    shift_ = 64 - std::countr_zero(slots_.size());
  }
  // Keys must not be all ones (the empty mark); octant keys never are.
  void add(uint64_t key) { slots_[find_slot(key)] = key; }
  bool contains(uint64_t key) const { return slots_[find_slot(key)] == key; }
  // Starts loading the cache line where a lookup of `key` begins: a caller
  // with many lookups to make prefetches them all first, so their misses
  // overlap instead of following one another.
  void prefetch(uint64_t key) const {
    __builtin_prefetch(&slots_[(key * 0x9E3779B97F4A7C15ULL) >> shift_]);
  }

 private:
  static constexpr uint64_t kEmpty = ~uint64_t{0};

  size_t find_slot(uint64_t key) const { return probe_slot(slots_, shift_, key, kEmpty); }

  std::vector<uint64_t> slots_;
  int shift_ = 58;
};

}  // namespace weaver
