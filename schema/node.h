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

// Trailing zero bits of a node coordinate; 0 counts as 31 (a multiple of everything).
constexpr int coord_zeros(uint32_t v) { return v == 0 ? 31 : std::countr_zero(v); }

// The anchors of a dangling node, in ascending node-key order (which is the
// order of their node ids).  Returns how many (2 or 4), or 0 for an anchored
// node.  Accepts: node coordinates of a dangling node of that kind.
inline int node_anchors(Coord n, NodeKind kind, Coord out[4]) {
  if (kind == NodeKind::kAnchored) return 0;
  const uint32_t c[3] = {n.x, n.y, n.z};
  const int z[3] = {coord_zeros(n.x), coord_zeros(n.y), coord_zeros(n.z)};
  const int low = std::min(z[0], std::min(z[1], z[2]));
  const uint32_t h = uint32_t{1} << low;
  int axes[2], count = 0;
  for (int a = 0; a < 3 && count < 2; ++a) {
    if (z[a] == low) axes[count++] = a;
  }
  const int corners = kind == NodeKind::kEdge ? 2 : 4;
  for (int k = 0; k < corners; ++k) {
    uint32_t p[3] = {c[0], c[1], c[2]};
    p[axes[0]] = (k & 1) ? c[axes[0]] + h : c[axes[0]] - h;
    if (kind == NodeKind::kFace) p[axes[1]] = (k & 2) ? c[axes[1]] + h : c[axes[1]] - h;
    out[k] = {p[0], p[1], p[2]};
  }
  // Sort by node key (at most 4 items).
  for (int i = 1; i < corners; ++i) {
    for (int j = i; j > 0 && morton_encode(out[j]) < morton_encode(out[j - 1]); --j) {
      const Coord t = out[j];
      out[j] = out[j - 1];
      out[j - 1] = t;
    }
  }
  return corners;
}

// node_anchors' answer as node keys (Morton codes), from the node's key
// alone, without decoding it: an axis whose coordinate has the fewest
// trailing zeros has its lowest set bit at 3 * zeros + axis, the fewest
// being a third of the key's trailing zeros.  Ascending.  For checks of
// every dangling node (weaver verify), where decoding, re-encoding and
// sorting coordinates cost more than the lookups of the anchors.
// Accepts: the key of a dangling node of that kind.
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

}  // namespace weaver
