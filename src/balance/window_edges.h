// Which of a leaf's neighbours can lie outside its balance window: the
// window's leaves ask for the layer leaves meeting these (window_balance.h).
// A window is a run of keys [from, to); the coarsest octant inside it that
// holds a leaf answers for all the leaf's neighbours that stay inside that
// octant, so only the sides of it the leaf touches are looked across.
#pragma once

#include <array>
#include <bit>
#include <cstdint>

#include "schema/octant.h"

namespace weaver::window_edges {

// Whether [key, end of its subtree) lies in [from, to).
inline bool within(uint64_t key, uint64_t from, uint64_t to) {
  return key >= from && octant_key_subtree_end(key) <= to;
}

// The sides of its ancestor at level `a` that leaf `key` touches: bit 2k
// the low side along axis k, bit 2k + 1 the high one (all six when the
// leaf is the ancestor).  Along each axis, the leaf's coordinate bits
// between the two levels are all 0 or all 1 there; read from the Morton
// code, without decoding.  None: the leaf's 3 x 3 x 3 block lies inside.
inline unsigned touched_sides(uint64_t key, int a) {
  const int l = octant_key_level(key);
  if (l == a) return 63;
  const uint64_t m = octant_key_morton(key);
  const uint64_t range =
      ((uint64_t{1} << (3 * (kMaxLevel - a))) - 1) & ~((uint64_t{1} << (3 * (kMaxLevel - l))) - 1);
  unsigned sides = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const uint64_t bits = (uint64_t{0x9249249249249249} << axis) & range;
    const uint64_t mine = m & bits;
    if (mine == 0) sides |= 1u << (2 * axis);
    if (mine == bits) sides |= 1u << (2 * axis + 1);
  }
  return sides;
}

// By the sides touched, the directions (a bit each, as in kAllDirections)
// whose steps cross touched sides: some of them (every = false), or all of
// them (every = true).
constexpr std::array<uint32_t, 64> directions_by_sides(bool every) {
  std::array<uint32_t, 64> t{};
  for (unsigned sides = 0; sides < 64; ++sides) {
    for (size_t i = 0; i < kAllDirections.size(); ++i) {
      const int step[3] = {kAllDirections[i].dx, kAllDirections[i].dy, kAllDirections[i].dz};
      int steps = 0, crossing = 0;
      for (int axis = 0; axis < 3; ++axis) {
        if (step[axis] == 0) continue;
        ++steps;
        crossing += (sides >> (2 * axis + (step[axis] > 0 ? 1 : 0))) & 1;
      }
      if (every ? crossing == steps : crossing > 0) t[sides] |= 1u << i;
    }
  }
  return t;
}
// The directions whose neighbour of a leaf crosses one of the sides it
// touches.
inline constexpr std::array<uint32_t, 64> kCrossing = directions_by_sides(false);
// The same-size neighbours of the holding octant (by their direction) that
// the leaf's own neighbours can lie in: those across touched sides only.
inline constexpr std::array<uint32_t, 64> kReachable = directions_by_sides(true);

// The same-size neighbours of octant `key` (a bit each, as in
// kAllDirections) not wholly inside [from, to): a leaf of it can ask for
// octants outside the window only across these.
inline uint32_t neighbours_leaving(uint64_t key, uint64_t from, uint64_t to) {
  if (octant_key_level(key) == kMaxLevel) return ~uint32_t{0};  // (no same-size steps)
  uint32_t out = 0;
  for (size_t i = 0; i < kAllDirections.size(); ++i) {
    uint64_t nb = 0;
    if (octant_key_neighbour(key, kAllDirections[i], &nb) && !within(nb, from, to)) {
      out |= 1u << i;
    }
  }
  return out;
}

}  // namespace weaver::window_edges
