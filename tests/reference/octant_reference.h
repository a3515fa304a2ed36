// Slow, obviously correct twins of the bit tricks in schema/.  Each one is
// written from the definition (loops over bits, interval arithmetic,
// enumeration) so that a test comparing the two checks the fast version.
#pragma once

#include <cstdint>
#include <tuple>

#include "schema/octant.h"

namespace weaver::reference {

inline uint64_t morton_encode(uint32_t x, uint32_t y, uint32_t z) {
  uint64_t code = 0;
  for (int i = 0; i < 21; ++i) {
    code |= uint64_t{(x >> i) & 1} << (3 * i);
    code |= uint64_t{(y >> i) & 1} << (3 * i + 1);
    code |= uint64_t{(z >> i) & 1} << (3 * i + 2);
  }
  return code;
}

inline Coord morton_decode(uint64_t code) {
  Coord c;
  for (int i = 0; i < 21; ++i) {
    c.x |= static_cast<uint32_t>((code >> (3 * i)) & 1) << i;
    c.y |= static_cast<uint32_t>((code >> (3 * i + 1)) & 1) << i;
    c.z |= static_cast<uint32_t>((code >> (3 * i + 2)) & 1) << i;
  }
  return c;
}

inline uint64_t edge(int level) {
  uint64_t e = 1;
  for (int i = level; i < kMaxLevel; ++i) e *= 2;
  return e;
}

// The order of DESIGN.md: Morton code of the corner, then level.
inline bool key_less(const Octant& a, const Octant& b) {
  const uint64_t ma = morton_encode(a.x, a.y, a.z), mb = morton_encode(b.x, b.y, b.z);
  return std::tie(ma, a.level) < std::tie(mb, b.level);
}

inline Octant parent(const Octant& o) {
  const uint64_t e = edge(o.level - 1);
  return {static_cast<uint32_t>(o.x / e * e), static_cast<uint32_t>(o.y / e * e),
          static_cast<uint32_t>(o.z / e * e), static_cast<uint8_t>(o.level - 1)};
}

inline Octant child(const Octant& o, int k) {
  const uint64_t h = edge(o.level + 1);
  return {static_cast<uint32_t>(o.x + (k % 2) * h), static_cast<uint32_t>(o.y + (k / 2 % 2) * h),
          static_cast<uint32_t>(o.z + (k / 4 % 2) * h), static_cast<uint8_t>(o.level + 1)};
}

inline bool contains_point(const Octant& o, uint64_t x, uint64_t y, uint64_t z) {
  const uint64_t e = edge(o.level);
  return o.x <= x && x < o.x + e && o.y <= y && y < o.y + e && o.z <= z && z < o.z + e;
}

// a strictly contains b as a box, and is coarser.
inline bool is_ancestor(const Octant& a, const Octant& b) {
  const uint64_t ea = edge(a.level), eb = edge(b.level);
  return a.level < b.level && a.x <= b.x && b.x + eb <= a.x + ea && a.y <= b.y &&
         b.y + eb <= a.y + ea && a.z <= b.z && b.z + eb <= a.z + ea;
}

inline Octant nearest_common_ancestor(Octant a, const Octant& b) {
  while (!(a == b || is_ancestor(a, b))) a = parent(a);
  return a;
}

inline bool neighbour(const Octant& o, int dx, int dy, int dz, Octant* out) {
  const int64_t e = static_cast<int64_t>(edge(o.level));
  const int64_t x = o.x + dx * e, y = o.y + dy * e, z = o.z + dz * e;
  const int64_t root = static_cast<int64_t>(edge(0));
  if (x < 0 || y < 0 || z < 0 || x >= root || y >= root || z >= root) return false;
  *out = {static_cast<uint32_t>(x), static_cast<uint32_t>(y), static_cast<uint32_t>(z), o.level};
  return true;
}

inline int child_id(const Octant& o) {
  const Octant p = parent(o);
  for (int k = 0; k < 8; ++k) {
    if (child(p, k) == o) return k;
  }
  return -1;
}

}  // namespace weaver::reference
