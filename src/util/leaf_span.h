// The box a set of leaves spans (ticks) and whether their volumes fill it:
// the boundary's scan finds it over the octant table, construct over the
// leaves it writes (so that `weaver mesh` need not scan for it).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "schema/octant.h"

namespace weaver {

struct LeafSpan {
  std::array<uint32_t, 3> lo{UINT32_MAX, UINT32_MAX, UINT32_MAX}, hi{};  // hi: the far side
  unsigned __int128 volume = 0;
  bool filled = true;

  void add(const Octant& o) {
    const uint32_t e = octant_edge(o), c[3] = {o.x, o.y, o.z};
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], c[a]);
      hi[a] = std::max(hi[a], c[a] + e);
    }
    volume += static_cast<unsigned __int128>(uint64_t{e} * e) * e;
  }
  void add(const LeafSpan& s) {
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], s.lo[a]), hi[a] = std::max(hi[a], s.hi[a]);
    volume += s.volume;
  }
  // Once every leaf is in: whether they fill the box.
  void settle() {
    if (volume == 0) return;
    unsigned __int128 box = 1;
    for (int a = 0; a < 3; ++a) box *= hi[a] - lo[a];
    filled = volume == box;
  }
};

}  // namespace weaver
