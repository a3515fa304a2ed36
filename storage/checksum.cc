#include "storage/checksum.h"

#include <bit>
#include <cstring>

namespace weaver {
namespace {

// Odd constants with well-mixed bits (digits of the golden ratio and of pi);
// any odd 64-bit constants with dense bit patterns would do.
constexpr uint64_t kMulA = 0x9E3779B97F4A7C15ULL;
constexpr uint64_t kMulB = 0xC2B2AE3D27D4EB4FULL;
constexpr uint64_t kMulC = 0x243F6A8885A308D3ULL;

inline uint64_t load64(const unsigned char* p) {
  uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

inline uint64_t mix_lane(uint64_t lane, uint64_t word) {
  lane += word * kMulB;
  lane = std::rotl(lane, 31);
  return lane * kMulA;
}

inline uint64_t finish(uint64_t h) {
  h ^= h >> 33;
  h *= kMulB;
  h ^= h >> 29;
  h *= kMulC;
  h ^= h >> 32;
  return h;
}

}  // namespace

uint32_t checksum32(const void* data, size_t n) {
  const auto* p = static_cast<const unsigned char*>(data);
  uint64_t a = kMulA, b = kMulB, c = kMulC, d = kMulA ^ kMulC;
  size_t i = 0;
  for (; i + 32 <= n; i += 32) {
    a = mix_lane(a, load64(p + i));
    b = mix_lane(b, load64(p + i + 8));
    c = mix_lane(c, load64(p + i + 16));
    d = mix_lane(d, load64(p + i + 24));
  }
  uint64_t h = std::rotl(a, 1) + std::rotl(b, 7) + std::rotl(c, 12) + std::rotl(d, 18);
  for (; i + 8 <= n; i += 8) h = mix_lane(h, load64(p + i));
  for (; i < n; ++i) h = mix_lane(h, p[i]);
  h ^= n;
  return static_cast<uint32_t>(finish(h));
}

}  // namespace weaver
