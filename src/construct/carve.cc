#include "construct/carve.h"

#include <algorithm>
#include <cstring>

#include "construct/descent.h"

namespace weaver {
namespace {

// The descent's side, where it is sure of it, is the box's own: only a cut
// leaf's fraction is computed.
double fraction_of(const ConstructPlan& p, const Octant& o, GroundSide side) {
  if (side == GroundSide::kSolid) return 1;
  if (side == GroundSide::kAir) return 0;
  const double e = octant_edge(o) * p.tick_m;
  const double lo[3] = {o.x * p.tick_m, o.y * p.tick_m, o.z * p.tick_m};
  const double hi[3] = {lo[0] + e, lo[1] + e, lo[2] + e};
  return solid_fraction(p.ground, lo, hi);
}

}  // namespace

void carve_leaves(const ConstructPlan& p, size_t bytes, SubtreeLeaves* leaves, uint64_t* air,
                  uint64_t* cut) {
  size_t kept = 0;
  leaves->levels = {};
  for (size_t i = 0; i < leaves->keys.size(); ++i) {
    const Octant o = octant_from_key(leaves->keys[i]);
    const double f = fraction_of(p, o, leaves->sides[i]);
    if (f <= 0) {
      ++*air;
      continue;
    }
    if (f < 1) ++*cut;
    const float solid = static_cast<float>(f);
    std::byte* dst = leaves->payloads.data() + kept * bytes;
    if (kept != i) {
      leaves->keys[kept] = leaves->keys[i];
      std::memmove(dst, leaves->payloads.data() + i * bytes, bytes);
    }
    std::memcpy(dst + bytes - 4, &solid, 4);
    leaves->span.add(o);
    ++leaves->levels[o.level];
    ++kept;
  }
  leaves->keys.resize(kept);
  leaves->sides.clear();
  leaves->payloads.resize(kept * bytes);
  leaves->elements = kept;
  bool first = true;
  for (int l = 0; l <= kMaxLevel; ++l) {
    if (leaves->levels[l] == 0) continue;
    const double edge_m = octant_edge(l) * p.tick_m;
    if (first) leaves->largest_edge_m = edge_m;
    leaves->smallest_edge_m = edge_m;
    first = false;
  }
}

}  // namespace weaver
