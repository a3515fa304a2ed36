// An open-addressing set of octant keys of one level, sized once for a known
// number of keys: 8 bytes a slot, at most a quarter of the slots used.
//
// Balance asks it about the 18 neighbours of each octant of a chunk taken in
// Z-order.  A plain hash sends each of those to a random cache line of a
// table far larger than the cache; here the table is cut into regions of 64
// slots, one per 4 x 4 x 4 block of cells, and a cell's slot is its place in
// its block's region (regions are placed by a hash of the block).  The
// neighbours of a cell mostly lie in its own block or the next one, whose
// regions the octants just before it have loaded already.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <vector>

#include "schema/octant.h"

namespace weaver {

// Linear probing from `start`: the slot holding `key`, or the empty slot
// where it would go.
inline size_t probe_slot_from(const std::vector<uint64_t>& slots, size_t start, uint64_t key,
                              uint64_t empty) {
  size_t s = start;
  while (slots[s] != empty && slots[s] != key) s = (s + 1) & (slots.size() - 1);
  return s;
}

// The same from the key's Fibonacci hash (top bits, `shift` = 64 - log2 of
// the slot count), for keys without locality to keep.
inline size_t probe_slot(const std::vector<uint64_t>& slots, int shift, uint64_t key,
                         uint64_t empty) {
  return probe_slot_from(slots, (key * 0x9E3779B97F4A7C15ULL) >> shift, key, empty);
}

class KeySet {
 public:
  // The slot count for `keys` keys: the least power of two >= 4 * keys.
  static size_t slots_for(size_t keys) {
    return std::bit_ceil(std::max<size_t>(kRegion, 4 * keys));
  }

  // Empties the set and makes room for `keys` keys; adding more is a bug.
  void reset(size_t keys) {
    slots_.assign(slots_for(keys), kEmpty);
    region_bits_ = std::countr_zero(slots_.size() / kRegion);
  }
  // REQUIRES: octant keys below level 20, all of one level.
  void add(uint64_t key) { slots_[probe_slot_from(slots_, start(key), key, kEmpty)] = key; }
  bool contains(uint64_t key) const {
    return slots_[probe_slot_from(slots_, start(key), key, kEmpty)] == key;
  }
  // Starts loading the cache line where a lookup of `key` begins: a caller
  // with many lookups to make prefetches them all first, so their misses
  // overlap instead of following one another.
  void prefetch(uint64_t key) const { __builtin_prefetch(&slots_[start(key)]); }

 private:
  static constexpr uint64_t kEmpty = ~uint64_t{0};
  static constexpr size_t kRegion = 64;

  // The first slot to probe: the cell's place within its block's region.
  size_t start(uint64_t key) const {
    const int level = octant_key_level(key);
    // The Morton index at the level: key >> 7 is the Morton code over 8.
    const uint64_t cell = (key >> 7) >> (3 * (kMaxLevel - level) - 3);
    const uint64_t hash = (cell >> 6) * 0x9E3779B97F4A7C15ULL;
    const uint64_t region = region_bits_ == 0 ? 0 : hash >> (64 - region_bits_);
    return static_cast<size_t>(region * kRegion + (cell & (kRegion - 1)));
  }

  std::vector<uint64_t> slots_;
  int region_bits_ = 0;
};

}  // namespace weaver
