// The boundary faces of a set of leaves (db/boundary_table.h), straight
// from the definition: for each face of each leaf, the box the leaves span
// says whether it lies on the domain's side; otherwise each quarter of the
// face is open when no leaf holds the pixel just across it at the
// quarter's first corner (exact for leaves no finer than twice across a
// face, as a 2:1 balanced octree and any subset of one are).  A slow twin
// of boundary/boundary.cc.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "schema/octant.h"

namespace weaver::reference {

struct BoundaryFace {
  uint64_t element;
  int face, part;
  int kind;  // 0 domain side, 1 free surface
  bool operator==(const BoundaryFace& o) const {
    return element == o.element && face == o.face && part == o.part && kind == o.kind;
  }
};

// leaves: in key order.
inline std::vector<BoundaryFace> boundary(const std::vector<Octant>& leaves) {
  std::array<int64_t, 3> lo{INT64_MAX, INT64_MAX, INT64_MAX}, hi{0, 0, 0};
  for (const Octant& o : leaves) {
    const int64_t c[3] = {o.x, o.y, o.z}, e = octant_edge(o);
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a] + e);
  }
  // Whether a leaf holds pixel p (coordinates may lie outside the root).
  auto held = [&](const int64_t p[3]) {
    for (int a = 0; a < 3; ++a) {
      if (p[a] < 0 || p[a] >= int64_t(kRootEdge)) return false;
    }
    const Coord c{uint32_t(p[0]), uint32_t(p[1]), uint32_t(p[2])};
    const uint64_t key = octant_key(Octant{c.x, c.y, c.z, kMaxLevel});
    auto it = std::upper_bound(leaves.begin(), leaves.end(), key,
                               [](uint64_t k, const Octant& o) { return k < octant_key(o); });
    return it != leaves.begin() && octant_contains_point(*(it - 1), c);
  };
  std::vector<BoundaryFace> out;
  for (size_t id = 0; id < leaves.size(); ++id) {
    const Octant& o = leaves[id];
    const int64_t c[3] = {o.x, o.y, o.z}, e = octant_edge(o);
    for (int f = 0; f < 6; ++f) {
      const int a = f / 2, side = f & 1;
      const int u = a == 0 ? 1 : 0, v = a == 2 ? 1 : 2;
      if (side ? c[a] + e == hi[a] : c[a] == lo[a]) {
        out.push_back({id, f, 0, f == 4 ? 1 : 0});
        continue;
      }
      const int quarters = e >= 2 ? 4 : 1;
      bool open[4] = {};
      int n_open = 0;
      for (int q = 0; q < quarters; ++q) {
        int64_t p[3] = {c[0], c[1], c[2]};
        p[a] = side ? c[a] + e : c[a] - 1;
        p[u] += (q & 1) * (e / 2);
        p[v] += (q >> 1) * (e / 2);
        open[q] = !held(p);
        n_open += open[q];
      }
      if (n_open == quarters) {
        out.push_back({id, f, 0, 1});
      } else {
        for (int q = 0; q < quarters; ++q) {
          if (open[q]) out.push_back({id, f, q + 1, 1});
        }
      }
    }
  }
  return out;
}

}  // namespace weaver::reference
