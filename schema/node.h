// Mesh nodes: kinds, and the anchors a dangling node depends on.
//
// A node at the midpoint of an edge of some element is edge-dangling and
// depends on the edge's 2 endpoints; one at the centre of a face of some
// element is face-dangling and depends on the face's 4 corners; all other
// nodes are anchored.  The anchors follow from the coordinate and kind alone:
// an edge midpoint has exactly one axis with the fewest trailing zero bits
// (the edge's axis, h = 2^zeros the half edge); a face centre has exactly
// two (the face's axes).  So a node table stores the kind and nothing else.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>

#include "schema/morton.h"

namespace weaver {

enum class NodeKind : uint8_t { kAnchored = 0, kEdge = 1, kFace = 2 };  // on disk

// "anchored", "edge" or "face": the names the CSV export and messages use.
constexpr const char* node_kind_name(NodeKind k) {
  switch (k) {
    case NodeKind::kAnchored: return "anchored";
    case NodeKind::kEdge: return "edge";
    case NodeKind::kFace: return "face";
  }
  return "?";
}

// The anchors of a dangling node as node keys (Morton codes), ascending
// (which is the order of their node ids), from the node's key alone: an
// axis whose coordinate has the fewest trailing zeros has its lowest set
// bit at 3 * zeros + axis, the fewest being a third of the key's trailing
// zeros, and the anchors are h = 2^zeros either way along the first one
// (edge) or two (face) such axes.  Returns how many (2 or 4), or 0 for an
// anchored node.  Accepts: the key of a dangling node of that kind.
inline int node_anchor_keys(uint64_t m, NodeKind kind, uint64_t out[4]) {
  if (kind == NodeKind::kAnchored || m == 0) return 0;
  const int low = std::countr_zero(m) / 3;
  const unsigned lowest = static_cast<unsigned>(m >> (3 * low)) & 7;  // the axes at `low`
  const int a0 = std::countr_zero(lowest);
  const uint64_t down = morton_step_back(m, a0, low), up = morton_step(m, a0, low);
  if (kind == NodeKind::kEdge) {
    out[0] = down, out[1] = up;
    return 2;
  }
  const unsigned rest = lowest & (lowest - 1);
  const int a1 = rest == 0 ? a0 : std::countr_zero(rest);
  out[0] = morton_step_back(down, a1, low), out[1] = morton_step_back(up, a1, low);
  out[2] = morton_step(down, a1, low), out[3] = morton_step(up, a1, low);
  std::sort(out, out + 4);
  return 4;
}

// node_anchor_keys' anchors as coordinates, in the same order.
// Accepts: node coordinates of a dangling node of that kind.
inline int node_anchors(Coord n, NodeKind kind, Coord out[4]) {
  uint64_t keys[4];
  const int count = node_anchor_keys(morton_encode(n), kind, keys);
  for (int i = 0; i < count; ++i) out[i] = morton_decode(keys[i]);
  return count;
}

}  // namespace weaver
