// A bucket's nodal pixels as words: a node's offset from the bucket's start
// (key - start, less the trailing zero bits every key of the bucket shares)
// above its 8-bit direction mask, in an open-addressing table of such
// words.  The words are what the bucket's radix sort sorts, so none is
// packed after hashing, and a slot is one load, not a key and a mask.

#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <vector>

namespace weaver {

class NodeWords {
 public:
  // The widest offset a word holds beside its mask: 55 bits, so that no
  // word has the top bit set and none is the empty slot's all ones.
  static constexpr int kOffsetBits = 55;

  // Empties the table, with room for `expected` offsets without growing.
  // A table of the same size is emptied slot by used slot.
  void reset(size_t expected) {
    const size_t cap = std::bit_ceil(std::max<size_t>(64, 2 * expected));
    if (cap == slots_.size()) {
      for (size_t i = 0; i < count_; ++i) slots_[used_[i]] = kEmpty;
    } else {
      slots_.assign(cap, kEmpty);
      used_.resize(cap / 2 + 1);
    }
    count_ = 0;
    limit_ = cap / 2;
    shift_ = 64 - std::countr_zero(cap);
  }

  // ORs bits into the offset's mask, adding the offset if new, without a
  // branch on whether it is: a block's far-face corners are new or its
  // neighbours' by turns, so such a branch is a poor guess (inferred from
  // the profile: this machine's perf counts no mispredictions; the gain
  // measured was within the noise).  REQUIRES: offset < 2^kOffsetBits.
  void add(uint64_t offset, uint8_t bits) {
    if (count_ >= limit_) grow();
    const size_t mask = slots_.size() - 1;
    size_t s = start(offset);
    uint64_t w = slots_[s];
    // Empty (~w zero) or this offset's ((w >> 8) ^ offset zero): one test,
    // so one branch, taken only on a collision (written as two tests, the
    // compiler branched on each).
    while (std::min((w >> 8) ^ offset, ~w) != 0) s = (s + 1) & mask, w = slots_[s];
    const bool fresh = w == kEmpty;
    slots_[s] = (fresh ? offset << 8 : w) | bits;
    used_[count_] = static_cast<uint32_t>(s);  // kept only if fresh
    count_ += fresh;
  }

  size_t size() const { return count_; }

  // The words added since reset (insertion order) into *out; returns them
  // ORed together (whose bits above the mask bound every offset's).
  uint64_t take(std::vector<uint64_t>* out) const {
    out->resize(count_);
    uint64_t all = 0;
    for (size_t i = 0; i < count_; ++i) all |= (*out)[i] = slots_[used_[i]];
    return all;
  }

 private:
  static constexpr uint64_t kEmpty = ~uint64_t{0};

  // The first slot to probe: the offset's Fibonacci hash.  (Slots kept
  // near for neighbouring points, by blocks of 64 as KeySet keeps them,
  // took the 1 Hz extract 1.1x the time of this hash, farm-bench's 5
  // pairs; likely the corners of coarse leaves, few to a block, crowd the
  // same slots of their blocks' regions.)
  size_t start(uint64_t offset) const {
    return static_cast<size_t>((offset * 0x9E3779B97F4A7C15ULL) >> shift_);
  }

  void grow() {
    std::vector<uint64_t> words;
    take(&words);
    reset(slots_.size());  // twice the slots: reset sizes for 2x
    for (uint64_t w : words) add(w >> 8, static_cast<uint8_t>(w));
  }

  std::vector<uint64_t> slots_;
  std::vector<uint32_t> used_;  // the slots holding words: [0, count_)
  // Neither a uint64_t nor a uint32_t (an unsigned long and an unsigned
  // int here): a store to a slot or to used_ could alias them, and each
  // would be loaded again after every add.
  unsigned long long count_ = 0, limit_ = 0;  // at most half the slots are used: past it, grow
  int shift_ = 58;
};

}  // namespace weaver
