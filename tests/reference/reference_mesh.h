// Slow, obviously correct references for the mesh stages: a 2:1 balancer and
// a mesh extractor, both straight from the definitions, by brute force over
// the leaf list.  For small octrees only (quadratic).
#pragma once

#include <algorithm>
#include <array>
#include <map>
#include <set>
#include <stdexcept>
#include <vector>

#include "schema/node.h"
#include "schema/octant.h"

namespace weaver::reference {

// Closed boxes of two leaves with disjoint interiors meet in a face or an
// edge (not just a point, not at all).
inline bool face_or_edge_adjacent(const Octant& a, const Octant& b) {
  const int64_t ea = octant_edge(a), eb = octant_edge(b);
  const int64_t alo[3] = {a.x, a.y, a.z}, blo[3] = {b.x, b.y, b.z};
  int positive = 0;
  for (int i = 0; i < 3; ++i) {
    const int64_t lo = std::max(alo[i], blo[i]), hi = std::min(alo[i] + ea, blo[i] + eb);
    if (hi < lo) return false;  // apart on this axis
    if (hi > lo) ++positive;
  }
  return positive >= 1;
}

// Closed boxes of two leaves with disjoint interiors share a piece of face
// of positive area: they touch on one axis and overlap on the other two.
inline bool face_adjacent(const Octant& a, const Octant& b) {
  const int64_t ea = octant_edge(a), eb = octant_edge(b);
  const int64_t alo[3] = {a.x, a.y, a.z}, blo[3] = {b.x, b.y, b.z};
  int touching = 0, overlapping = 0;
  for (int i = 0; i < 3; ++i) {
    const int64_t lo = std::max(alo[i], blo[i]), hi = std::min(alo[i] + ea, blo[i] + eb);
    touching += hi == lo;
    overlapping += hi > lo;
  }
  return touching == 1 && overlapping == 2;
}

// Splits any leaf with a face or edge neighbour two or more levels finer,
// until none is left.
inline std::vector<Octant> balance(std::vector<Octant> leaves) {
  bool changed = true;
  while (changed) {
    changed = false;
    std::vector<Octant> next;
    for (const Octant& l : leaves) {
      bool split = false;
      for (const Octant& k : leaves) {
        if (k.level >= l.level + 2 && face_or_edge_adjacent(l, k)) {
          split = true;
          break;
        }
      }
      if (split) {
        for (int c = 0; c < 8; ++c) next.push_back(octant_child(l, c));
        changed = true;
      } else {
        next.push_back(l);
      }
    }
    leaves = std::move(next);
  }
  std::sort(leaves.begin(), leaves.end(),
            [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
  return leaves;
}

struct MeshNode {
  Coord c;
  NodeKind kind = NodeKind::kAnchored;
  std::vector<uint64_t> anchors;  // node ids, ascending
};

struct Mesh {
  std::vector<Octant> elements;                  // id order
  std::vector<std::array<uint64_t, 8>> corners;  // node ids of corners 0..7
  std::vector<MeshNode> nodes;                   // id order
};

// Nodes are all element corners; a node is edge- (face-) dangling when it is
// the midpoint of an edge (centre of a face) of some element, depending on
// that edge's endpoints (that face's corners).
inline Mesh extract(std::vector<Octant> leaves) {
  std::sort(leaves.begin(), leaves.end(),
            [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
  std::map<uint64_t, Coord> by_key;
  for (const Octant& o : leaves)
    for (int k = 0; k < 8; ++k) by_key[node_key(octant_corner(o, k))] = octant_corner(o, k);
  Mesh m;
  m.elements = leaves;
  std::map<uint64_t, uint64_t> id;
  for (const auto& [key, c] : by_key) {
    id[key] = m.nodes.size();
    m.nodes.push_back({c, NodeKind::kAnchored, {}});
  }
  auto mark = [&](Coord p, NodeKind kind, std::vector<Coord> anchors) {
    auto it = id.find(node_key(p));
    if (it == id.end()) return;  // not a node
    MeshNode& n = m.nodes[it->second];
    std::vector<uint64_t> ids;
    for (const Coord& a : anchors) ids.push_back(id.at(node_key(a)));
    std::sort(ids.begin(), ids.end());
    if (n.kind != NodeKind::kAnchored && (n.kind != kind || n.anchors != ids)) {
      throw std::logic_error("reference: node dangles in two ways");
    }
    n.kind = kind;
    n.anchors = ids;
  };
  for (const Octant& o : leaves) {
    const uint32_t e = octant_edge(o), h = e / 2;
    if (h == 0) continue;  // a level-20 leaf has no interior midpoints
    for (int axis = 0; axis < 3; ++axis) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) {  // the 4 edges along `axis`
          uint32_t p[3] = {o.x, o.y, o.z}, a[3], b[3];
          p[u] += i * e;
          p[v] += j * e;
          std::copy(p, p + 3, a);
          std::copy(p, p + 3, b);
          b[axis] += e;
          p[axis] += h;
          mark({p[0], p[1], p[2]}, NodeKind::kEdge, {{a[0], a[1], a[2]}, {b[0], b[1], b[2]}});
        }
      for (int side = 0; side < 2; ++side) {  // the 2 faces normal to `axis`
        uint32_t p[3] = {o.x, o.y, o.z};
        p[axis] += side * e;
        std::vector<Coord> anchors;
        for (int k = 0; k < 4; ++k) {
          uint32_t q[3] = {p[0], p[1], p[2]};
          q[u] += (k & 1) * e;
          q[v] += ((k >> 1) & 1) * e;
          anchors.push_back({q[0], q[1], q[2]});
        }
        p[u] += h;
        p[v] += h;
        mark({p[0], p[1], p[2]}, NodeKind::kFace, anchors);
      }
    }
  }
  for (const Octant& o : leaves) {
    std::array<uint64_t, 8> c;
    for (int k = 0; k < 8; ++k) c[k] = id.at(node_key(octant_corner(o, k)));
    m.corners.push_back(c);
  }
  return m;
}

}  // namespace weaver::reference
