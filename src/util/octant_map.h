// An open-addressing map from octant keys to what the local balance of a
// subtree knows of them (subtree_balance.h): a leaf of the input, an
// inner octant of it (an ancestor of leaves), or an octant the balance
// creates inside a leaf.  The kind rides in bits 5 and 6 of the slot, which
// no octant key uses (its level slot is below 28), so a slot is 8 bytes.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <vector>

#include "util/huge_pages.h"

namespace weaver {

class OctantMap {
 public:
  enum Kind : uint64_t { kAbsent = 0, kLeaf = 1, kInner = 2, kCreated = 3 };

  // Empties the map and makes room for `keys` keys (a load of at most a
  // half; it grows past that).
  void reset(size_t keys) {
    count_ = 0;
    const size_t slots = std::bit_ceil(std::max<size_t>(128, 2 * keys));
    if (slots_.capacity() > 4 * slots) {
      fresh(slots, &slots_);  // give back what a larger set took
    } else if (slots_.size() != slots) {
      if (slots_.capacity() < slots) fresh(slots, &slots_);
      slots_.assign(slots, kEmpty);
    } else {
      std::fill(slots_.begin(), slots_.end(), kEmpty);
    }
    shift_ = 64 - std::countr_zero(slots);
  }

  Kind find(uint64_t key) const {
    const uint64_t s = slots_[probe(key)];
    return s == kEmpty ? kAbsent : static_cast<Kind>((s & kKindBits) >> kKindShift);
  }
  size_t bytes() const { return slots_.capacity() * sizeof(uint64_t); }
  // Starts loading the slot where a find of key begins.
  void prefetch(uint64_t key) const { __builtin_prefetch(&slots_[home(key)]); }
  // Adds key as `kind` unless it is present; true if it was added.
  bool add(uint64_t key, Kind kind) {
    uint64_t& s = slots_[probe(key)];
    if (s != kEmpty) return false;
    s = key | (uint64_t{kind} << kKindShift);
    if (++count_ * 2 > slots_.size()) grow();
    return true;
  }

 private:
  static constexpr uint64_t kEmpty = ~uint64_t{0};
  static constexpr int kKindShift = 5;
  static constexpr uint64_t kKindBits = uint64_t{3} << kKindShift;

  // The slot holding key, or the empty slot where it would go.  (A hash
  // that keeps a block of cells in one region of slots, as util/key_set.h
  // does, made the local balance a third slower here: a subtree's leaves
  // fill whole blocks, and the probes run long.)
  size_t probe(uint64_t key) const {
    const size_t mask = slots_.size() - 1;
    size_t i = home(key);
    while (slots_[i] != kEmpty && (slots_[i] & ~kKindBits) != key) i = (i + 1) & mask;
    return i;
  }

  size_t home(uint64_t key) const {
    return static_cast<size_t>((key * 0x9E3779B97F4A7C15ULL) >> shift_);
  }

  // A new array of n empty slots, in huge pages where the kernel gives
  // them: a window's map of millions of slots, faulted in 4 KiB at a time,
  // cost about a sixth of a random octree's balance.
  static void fresh(size_t n, std::vector<uint64_t>* out) {
    std::vector<uint64_t> v;
    reserve_huge(v, n);
    v.assign(n, kEmpty);
    out->swap(v);
  }

  void grow() {
    std::vector<uint64_t> old;
    fresh(2 * slots_.size(), &old);
    old.swap(slots_);
    shift_ -= 1;
    for (uint64_t s : old) {
      if (s != kEmpty) slots_[probe(s & ~kKindBits)] = s;
    }
  }

  std::vector<uint64_t> slots_;
  size_t count_ = 0;
  int shift_ = 64;
};

}  // namespace weaver
