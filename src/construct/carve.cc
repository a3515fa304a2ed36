#include "construct/carve.h"

#include <algorithm>
#include <cstring>

#include "construct/descent.h"

namespace weaver {
namespace {

constexpr int kFractionPoints = 8;

}  // namespace

double solid_fraction(const Ground& g, const double lo[3], const double hi[3]) {
  const GroundSide side = side_of_ground(g, lo, hi);
  if (side == GroundSide::kAir) return 0;
  if (side == GroundSide::kSolid) return 1;
  const double top = g.top_elevation, height = hi[2] - lo[2];
  const double sx = (hi[0] - lo[0]) / kFractionPoints, sy = (hi[1] - lo[1]) / kFractionPoints;
  double sum = 0;
  for (int j = 0; j < kFractionPoints; ++j) {
    for (int i = 0; i < kFractionPoints; ++i) {
      const double ground_z = top - g.ground_at(lo[0] + (i + 0.5) * sx, lo[1] + (j + 0.5) * sy);
      sum += std::clamp((hi[2] - std::max(lo[2], ground_z)) / height, 0.0, 1.0);
    }
  }
  const double f = sum / (kFractionPoints * kFractionPoints);
  if (f > 0) return f;
  // The ground reaches into the leaf between the points: the most it can
  // hold there, shared by one point's part.
  double g_lo, g_hi;
  g.surface->range(lo[0], hi[0], lo[1], hi[1], &g_lo, &g_hi);
  return std::min(1.0, (hi[2] - (top - g_hi)) / height) / (kFractionPoints * kFractionPoints);
}

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

void drop_air(SubtreeLeaves* leaves, size_t bytes, uint64_t* air) {
  size_t kept = 0;
  for (size_t i = 0; i < leaves->keys.size(); ++i) {
    if (leaves->sides[i] == GroundSide::kAir) {
      ++*air;
      continue;
    }
    if (kept != i) {
      leaves->keys[kept] = leaves->keys[i];
      leaves->sides[kept] = leaves->sides[i];
      std::memcpy(leaves->payloads.data() + kept * bytes, leaves->payloads.data() + i * bytes,
                  bytes);
    }
    ++kept;
  }
  leaves->keys.resize(kept);
  leaves->sides.resize(kept);
  leaves->payloads.resize(kept * bytes);
}

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
