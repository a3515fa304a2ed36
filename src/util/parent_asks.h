// What a parent asks of its face and edge neighbours in balance's level
// passes.  A leaf asks for the octants one level coarser that it touches:
// its parent's neighbours on the leaf's own sides.  So a parent whose
// leaves are known by child position asks for the union of their sides;
// a parent that lies wholly in the domain asks for all 18.
//
// A level's parents come as KeyTags from two spools.  An entry of the
// leaves' spool carries, instead of a leaf, the set of its children that
// are leaves, in a tag no octant key can have (slot 127); an entry of the
// required octants' spool carries a leaf that asked, for naming.
#pragma once

#include <array>
#include <cstdint>

#include "schema/octant.h"

namespace weaver::parent_asks {

inline constexpr uint64_t kChildrenSlot = 127;

constexpr uint64_t children_tag(unsigned children) {
  return (uint64_t{children} << 7) | kChildrenSlot;
}
constexpr bool is_children_tag(uint64_t tag) { return (tag & 127) == kChildrenSlot; }
constexpr unsigned children_of(uint64_t tag) { return static_cast<unsigned>(tag >> 7) & 255; }

namespace detail {
// Whether child c of an octant touches its neighbour in direction d: every
// step of d points to c's side.
constexpr bool touches(int c, Direction d) {
  const int step[3] = {d.dx, d.dy, d.dz};
  for (int axis = 0; axis < 3; ++axis) {
    const bool far_side = (c >> axis) & 1;
    if (step[axis] != 0 && (step[axis] > 0) != far_side) return false;
  }
  return true;
}
constexpr std::array<uint32_t, 256> touched_table() {
  std::array<uint32_t, 256> t{};
  for (unsigned children = 0; children < 256; ++children) {
    for (size_t i = 0; i < kFaceAndEdgeDirections.size(); ++i) {
      for (int c = 0; c < 8; ++c) {
        if ((children >> c & 1) && touches(c, kFaceAndEdgeDirections[i])) t[children] |= 1u << i;
      }
    }
  }
  return t;
}
constexpr std::array<uint8_t, kFaceAndEdgeDirections.size()> touching_table() {
  std::array<uint8_t, kFaceAndEdgeDirections.size()> t{};
  for (size_t i = 0; i < t.size(); ++i) {
    for (int c = 0; c < 8; ++c) {
      if (touches(c, kFaceAndEdgeDirections[i])) t[i] |= static_cast<uint8_t>(1u << c);
    }
  }
  return t;
}
}  // namespace detail

// Bit i: kFaceAndEdgeDirections[i].
inline constexpr uint32_t kAllNeighbours = (1u << kFaceAndEdgeDirections.size()) - 1;
// By set of children: the neighbours they touch.
inline constexpr std::array<uint32_t, 256> kTouchedBy = detail::touched_table();
// By direction: the children (a bit each) that touch that neighbour.
inline constexpr std::array<uint8_t, kFaceAndEdgeDirections.size()> kTouching =
    detail::touching_table();

static_assert(kTouchedBy[255] == kAllNeighbours);
static_assert(kTouchedBy[1] == 0b1'0110'0111);  // child 0: 3 faces, 3 edges

}  // namespace weaver::parent_asks
