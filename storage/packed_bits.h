// What the packed leaf's encoder, row dictionary and decoder share: the
// page's field offsets and codes, and the bit streams (format:
// storage/packed_leaf.h).  Internal to storage/packed_*.cc.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "schema/octant.h"
#include "storage/packed_leaf.h"
#include "storage/page_format.h"

namespace weaver::page::packed {

inline constexpr size_t kPgBlocks = 16, kPgFields = 18, kPgCoding = 19, kFieldsStart = 20,
                        kFieldBytes = 9;
inline constexpr uint8_t kCodingColumns = 0, kCodingDictionary = 1;
inline constexpr uint32_t kDictMinPayload = 4;
inline constexpr uint8_t kModeSuccessor = 0x80, kShiftMask = 0x3f;

inline uint64_t blocks_for(uint64_t n) { return (n + kPackedBlock - 1) / kPackedBlock; }
inline uint64_t bits_to_bytes(uint64_t bits) { return (bits + 7) / 8; }
inline uint64_t block_bytes(uint32_t count, uint32_t width) {
  return count <= 1 ? 0 : bits_to_bytes(uint64_t{count - 1} * width);
}

// The predicted next key of mode 1.  Defined for every u64 (damaged pages
// decode to garbage, never to undefined behaviour).
inline uint64_t successor(uint64_t key) { return octant_key_subtree_end_of_any(key); }

// successor(key) less the key's high bits (all but its 7-bit level slot),
// by slot: a level's subtree span, moved to the key's bits; for a level 20
// slot, the slot plus one (successor() is then key + 1); for the root, 0.
// A lookup, not successor()'s shift by a count in a register, which is
// several micro-ops on the processors we run on, for every octant key
// packed or read.
constexpr std::array<uint64_t, 128> successor_steps() {
  std::array<uint64_t, 128> step{};
  for (uint64_t slot = 1; slot < 128; ++slot) {
    step[slot] = slot >= kKeyLevel20Slot ? slot + 1 : uint64_t{1} << (3 * (kMaxLevel - slot) + 4);
  }
  return step;
}
inline constexpr std::array<uint64_t, 128> kSuccessorStep = successor_steps();

// The steps give successor()'s key; where it gives UINT64_MAX, a key no
// further than the high bits (or UINT64_MAX itself), which the readers of
// the table take for it.
constexpr bool steps_agree() {
  for (uint64_t slot = 0; slot < 128; ++slot) {
    for (const uint64_t high : {uint64_t{0}, uint64_t{0x1234567} << 20, ~uint64_t{0} << 8}) {
      const uint64_t key = (high & ~uint64_t{127}) | slot;
      const uint64_t e = octant_key_subtree_end_of_any(key), by_step = high + kSuccessorStep[slot];
      if (e != UINT64_MAX && e != by_step) return false;
      if (e == UINT64_MAX && by_step > high && by_step != UINT64_MAX) return false;
    }
  }
  return true;
}
static_assert(steps_agree());

// A field's raw little-endian bytes as an integer.  Fixed-size loads: a
// memcpy of a run-time size is a library call, and this is on every append.
inline uint64_t load_field(const std::byte* p, uint32_t size) {
  switch (size) {
    case 1: return static_cast<uint64_t>(p[0]);
    case 2: return load16(p);
    case 4: return load32(p);
    default: return load64(p);
  }
}

// Bits [pos, pos + w) of the stream at `base`, w <= 64.  Reads up to 9 bytes
// from byte pos/8: the page's slack keeps that inside the page.
inline uint64_t read_bits(const std::byte* base, uint64_t pos, uint32_t w) {
  const std::byte* p = base + (pos >> 3);
  const uint32_t s = pos & 7;
  uint64_t v = load64(p) >> s;
  if (s + w > 64) v |= static_cast<uint64_t>(p[8]) << (64 - s);
  return w >= 64 ? v : v & ((uint64_t{1} << w) - 1);
}

// Writes values of given widths one after another from a byte boundary,
// through a 64-bit accumulator: one store per 64 bits instead of a load and
// a store per value.  finish() stores the last word whole: up to 7 bytes of
// zeros past the bits, which the next region overwrites or the page's
// slack absorbs.
class BitWriter {
 public:
  explicit BitWriter(std::byte* at) : p_(at) {}
  void put(uint64_t v, uint32_t w) {
    if (w == 0) return;
    if (w < 64) v &= (uint64_t{1} << w) - 1;
    acc_ |= v << used_;
    const uint32_t total = used_ + w;
    if (total < 64) {
      used_ = total;
      return;
    }
    store64(p_, acc_);
    p_ += 8;
    used_ = total - 64;
    acc_ = used_ == 0 ? 0 : v >> (w - used_);
  }
  void finish() {
    if (used_ > 0) store64(p_, acc_);
  }

 private:
  std::byte* p_;
  uint64_t acc_ = 0;
  uint32_t used_ = 0;
};

// Decodes n values of a column (frame `min`, `w` bits each) into the field
// of n rows `stride` bytes apart.  T is the field's width; a fixed-size
// store and a shift-and-mask per value keep this close to a memcpy.
template <typename T>
inline void decode_column(const std::byte* col, uint32_t w, uint64_t min, uint32_t n,
                          std::byte* out, uint32_t stride) {
  if (w == 0) {
    const auto v = static_cast<T>(min);
    for (uint32_t i = 0; i < n; ++i, out += stride) std::memcpy(out, &v, sizeof v);
    return;
  }
  uint64_t pos = 0;
  if (w <= 56) {  // one unaligned load holds every value
    const uint64_t mask = (uint64_t{1} << w) - 1;
    for (uint32_t i = 0; i < n; ++i, out += stride, pos += w) {
      const auto v = static_cast<T>(min + ((load64(col + (pos >> 3)) >> (pos & 7)) & mask));
      std::memcpy(out, &v, sizeof v);
    }
    return;
  }
  for (uint32_t i = 0; i < n; ++i, out += stride, pos += w) {
    const auto v = static_cast<T>(min + read_bits(col, pos, w));
    std::memcpy(out, &v, sizeof v);
  }
}

// A hash of a payload row of `size` bytes.
inline uint64_t row_hash(const std::byte* p, uint32_t size) {
  uint64_t h = size;
  auto mix = [&h](uint64_t v) {
    h = (h ^ v) * 0x9E3779B97F4A7C15ULL;
    h ^= h >> 29;
  };
  // A material's 12 or 20 bytes by loads of sizes known when compiled (the
  // same hash as the loop below gives them: a short tail is zero-extended).
  if (size == 12 || size == 20) {
    mix(load64(p));
    mix(size == 12 ? load32(p + 8) : load64(p + 8));
    if (size == 20) mix(load32(p + 16));
    return h;
  }
  for (uint32_t at = 0; at < size; at += 8) {
    uint64_t v = 0;
    std::memcpy(&v, p + at, std::min<uint32_t>(8, size - at));
    mix(v);
  }
  return h;
}

// Whether two payload rows of `size` bytes are equal.  The common row
// sizes compare as fixed-size words, inline: a call to memcmp for each
// 12-byte material row was a few percent of construct.
inline bool rows_equal(const std::byte* a, const std::byte* b, uint32_t size) {
  switch (size) {
    case 12: return std::memcmp(a, b, 12) == 0;
    case 20: return std::memcmp(a, b, 20) == 0;
    default: return std::memcmp(a, b, size) == 0;
  }
}

}  // namespace weaver::page::packed
