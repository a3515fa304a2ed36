// Morton (Z-order) interleaving of three 21-bit coordinates into 63 bits.
//
// Bit i of x goes to bit 3i, of y to 3i+1, of z to 3i+2 (x least significant).
// This is fixed by DESIGN.md: keys on disk depend on it.
//
// Validity: every function here accepts coordinates in [0, 2^21), which
// covers node coordinates in [0, 2^20] (far side included). Callers that hold
// narrower classes (octant corners, pixels) may pass them unchanged.
#pragma once

#include <cstdint>
#include <type_traits>

#if defined(__x86_64__) && defined(__GNUC__)
#include <cpuid.h>
#endif

namespace weaver {

inline constexpr int kMortonBitsPerAxis = 21;
inline constexpr uint32_t kMortonAxisMask = (1u << kMortonBitsPerAxis) - 1;

struct Coord {
  uint32_t x = 0, y = 0, z = 0;
  friend bool operator==(const Coord&, const Coord&) = default;
};

namespace morton_detail {
// Where one axis's bits lie in a code: bits 0, 3, 6, ... (x; y and z above).
inline constexpr uint64_t kAxisBits = 0x1249249249249249ULL;
// Spreads the low 21 bits of v so that bit i lands on bit 3i.
constexpr uint64_t spread3(uint64_t v) {
  v &= kMortonAxisMask;
  v = (v | (v << 32)) & 0x001f00000000ffffULL;
  v = (v | (v << 16)) & 0x001f0000ff0000ffULL;
  v = (v | (v << 8)) & 0x100f00f00f00f00fULL;
  v = (v | (v << 4)) & 0x10c30c30c30c30c3ULL;
  v = (v | (v << 2)) & kAxisBits;
  return v;
}

// BMI2's PDEP and PEXT interleave and gather in one instruction each, where
// the processor runs them fast: every Intel core with BMI2, and AMD's from
// Zen 3 (family 0x19) on.  Zen 1 and 2 (family 0x17) and Hygon (0x18) run
// them in microcode, tens to hundreds of cycles: there the shifts above are
// faster.  Decided once per process; the codes are the same either way.
inline bool has_bit_deposit() {
#if defined(__x86_64__) && defined(__GNUC__)
  unsigned a = 0, b = 0, c = 0, d = 0;
  if (__get_cpuid_max(0, nullptr) < 7) return false;
  __cpuid_count(7, 0, a, b, c, d);
  return (b & (1u << 8)) != 0;  // BMI2
#else
  return false;
#endif
}
inline bool fast_bit_deposit() {
#if defined(__x86_64__) && defined(__GNUC__)
  if (!has_bit_deposit()) return false;
  unsigned a = 0, b = 0, c = 0, d = 0;
  __cpuid(0, a, b, c, d);
  const bool amd_or_hygon = b == 0x68747541 /* "Auth" */ || b == 0x6f677948 /* "Hygo" */;
  if (!amd_or_hygon) return true;
  __cpuid(1, a, b, c, d);
  const unsigned family = ((a >> 8) & 0xf) + ((a >> 8 & 0xf) == 0xf ? (a >> 20) & 0xff : 0);
  return family >= 0x19;
#else
  return false;
#endif
}
inline const bool kFastBitDeposit = fast_bit_deposit();

#if defined(__x86_64__) && defined(__GNUC__)
inline uint64_t deposit_bits(uint64_t v, uint64_t mask) {
  uint64_t r;
  asm("pdep %2, %1, %0" : "=r"(r) : "r"(v), "r"(mask));
  return r;
}
inline uint64_t extract_bits(uint64_t v, uint64_t mask) {
  uint64_t r;
  asm("pext %2, %1, %0" : "=r"(r) : "r"(v), "r"(mask));
  return r;
}
#define WEAVER_BIT_DEPOSIT 1
#endif

// Inverse of spread3: gathers bits 0, 3, 6, ... into the low 21 bits.
constexpr uint32_t compact3(uint64_t v) {
  v &= kAxisBits;
  v = (v | (v >> 2)) & 0x10c30c30c30c30c3ULL;
  v = (v | (v >> 4)) & 0x100f00f00f00f00fULL;
  v = (v | (v >> 8)) & 0x001f0000ff0000ffULL;
  v = (v | (v >> 16)) & 0x001f00000000ffffULL;
  v = (v | (v >> 32)) & kMortonAxisMask;
  return static_cast<uint32_t>(v);
}
}  // namespace morton_detail

// REQUIRES: x, y, z < 2^21.
constexpr uint64_t morton_encode(uint32_t x, uint32_t y, uint32_t z) {
#ifdef WEAVER_BIT_DEPOSIT
  if (!std::is_constant_evaluated() && morton_detail::kFastBitDeposit) {
    using morton_detail::deposit_bits, morton_detail::kAxisBits;
    return deposit_bits(x, kAxisBits) | deposit_bits(y, kAxisBits << 1) |
           deposit_bits(z, kAxisBits << 2);
  }
#endif
  return morton_detail::spread3(x) | (morton_detail::spread3(y) << 1) |
         (morton_detail::spread3(z) << 2);
}
constexpr uint64_t morton_encode(Coord c) { return morton_encode(c.x, c.y, c.z); }

// The Morton code of the point `code` decodes to, moved by 2^bit along axis
// (0 x, 1 y, 2 z), without decoding: the axis's bits are added as one
// dilated integer (the other axes' bits set to 1 carry the sum across them).
// REQUIRES: the moved coordinate stays below 2^21.
constexpr uint64_t morton_step(uint64_t code, int axis, int bit) {
  const uint64_t axis_bits = morton_detail::kAxisBits << axis;
  const uint64_t moved = ((code | ~axis_bits) + (uint64_t{1} << (3 * bit + axis))) & axis_bits;
  return moved | (code & ~axis_bits);
}

// The same, moved by -2^bit: the axis's bits alone (the others zero) lose
// one dilated unit, the borrow running across the zeros.
// REQUIRES: the moved coordinate is at least 2^bit.
constexpr uint64_t morton_step_back(uint64_t code, int axis, int bit) {
  const uint64_t axis_bits = morton_detail::kAxisBits << axis;
  const uint64_t moved = ((code & axis_bits) - (uint64_t{1} << (3 * bit + axis))) & axis_bits;
  return moved | (code & ~axis_bits);
}

// REQUIRES: code < 2^63.
constexpr Coord morton_decode(uint64_t code) {
#ifdef WEAVER_BIT_DEPOSIT
  if (!std::is_constant_evaluated() && morton_detail::kFastBitDeposit) {
    using morton_detail::extract_bits, morton_detail::kAxisBits;
    return Coord{uint32_t(extract_bits(code, kAxisBits)),
                 uint32_t(extract_bits(code, kAxisBits << 1)),
                 uint32_t(extract_bits(code, kAxisBits << 2))};
  }
#endif
  return Coord{morton_detail::compact3(code), morton_detail::compact3(code >> 1),
               morton_detail::compact3(code >> 2)};
}

}  // namespace weaver
