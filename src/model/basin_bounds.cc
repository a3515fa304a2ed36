#include "model/basin_bounds.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "model/basin_shape.h"

namespace weaver::basin {
namespace {

// A closed interval, empty until something is added.
struct Span {
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  void add(double v) { lo = std::min(lo, v), hi = std::max(hi, v); }
};
// Wider than any rounding of the arithmetic below (metres; m^2 relative).
constexpr double kDepthMargin = 1e-6, kRadiusMargin = 1e-9;

// The least and greatest squared distance from c to the points of [lo, hi]
// along one axis.
void axis_distance(double c, double lo, double hi, double* near2, double* far2) {
  const double near = std::max({lo - c, c - hi, 0.0});
  const double far = std::max(std::abs(lo - c), std::abs(hi - c));
  *near2 += near * near, *far2 += far * far;
}

// Bounds on sediment_depth over the columns of the box [lo, hi]: a bowl's
// dish deepens towards its centre, so its extremes over the rectangle are
// at the nearest and farthest points; the floor is the deepest bowl.
Span sediment_depth_span(const double lo[3], const double hi[3]) {
  double least = 0, most = 0;
  for (const Bowl& b : kBowls) {
    double near2 = 0, far2 = 0;
    axis_distance(b.cx, lo[0], hi[0], &near2, &far2);
    axis_distance(b.cy, lo[1], hi[1], &near2, &far2);
    // A product by 1 / r2, not a quotient (no division a bowl and side):
    // these are bounds, not at()'s values, and their rounding lies far
    // inside kDepthMargin.
    const double r2 = b.radius * b.radius, inv_r2 = 1 / r2;
    auto dish = [&](double d2) {
      const double q = 1 - d2 * inv_r2;
      return d2 >= r2 ? 0.0 : b.depth * q * q;
    };
    least = std::max(least, dish(far2));
    most = std::max(most, dish(near2));
  }
  Span s;
  s.lo = least - kDepthMargin, s.hi = most + kDepthMargin;
  return s;
}

enum class Reach { kNone, kSome, kAll };
// A box meeting more inclusion cells than this is said to meet an
// inclusion without looking: only coarse octants do, and they split.
constexpr uint64_t kMostCellsLooked = 27;

// The Vs of each kind of point the box [z_lo, z_hi] in depth may hold,
// over columns whose bowls' depth lies in `depth`: sediment[0..1] and
// rock[0..1] are each kind's Vs at z_lo and z_hi; reach() says whether
// its rock points may lie in an inclusion.
template <class ReachOf>
Span vs_span(double z_lo, double z_hi, const Span& depth, const float* sediment, const float* rock,
             const ReachOf& reach) {
  Span vs;
  if (z_lo < depth.hi) {  // some point may be above its floor
    vs.add(sediment[0]);
    vs.add(sediment[1]);
  }
  if (z_hi >= depth.lo) {  // some point may be in rock
    const Reach r = reach();
    if (r != Reach::kAll) {
      vs.add(rock[0]);
      vs.add(rock[1]);
    }
    if (r != Reach::kNone) vs.add(static_cast<float>(kInclusionVs));
  }
  return vs;
}

// The inclusion sites of a block of at most kMostCellsLooked cells.
struct SiteBlock {
  uint64_t first[3], size[3];
  bool has[kMostCellsLooked];
  double c[kMostCellsLooked][3];
  size_t at(uint64_t i, uint64_t j, uint64_t k) const {
    return ((k - first[2]) * size[1] + (j - first[1])) * size[0] + (i - first[0]);
  }
};
// The sites of the cells [first, last] (false: more than kMostCellsLooked).
bool find_sites(const uint64_t first[3], const uint64_t last[3], SiteBlock* b) {
  uint64_t cells = 1;
  for (int a = 0; a < 3; ++a) {
    b->first[a] = first[a], b->size[a] = last[a] - first[a] + 1;
    cells *= b->size[a];
  }
  if (cells > kMostCellsLooked) return false;
  size_t s = 0;
  for (uint64_t k = first[2]; k <= last[2]; ++k)
    for (uint64_t j = first[1]; j <= last[1]; ++j) {
      const uint64_t row = InclusionSite::row_hash(j, k);
      for (uint64_t i = first[0]; i <= last[0]; ++i, ++s) {
        const uint64_t h = InclusionSite::cell_hash(i, row);
        b->has[s] = InclusionSite::has_site(h);
        if (b->has[s]) InclusionSite::centre(i, j, k, h, b->c[s]);
      }
    }
  return true;
}

// Whether the rock points of [lo, hi] may lie in the spheres of the cells
// [first, last] (cells of them): some, all of the box, or none.  From a
// block of their sites found already, or (kFromBlock false) finding each as
// the loop reaches it, a row's hash once, so that the loop may stop at the
// first sphere holding the box (a block made first for one box cost a tenth
// more).  Two loops made from one: a branch a cell cost the other.
template <bool kFromBlock>
Reach reach_of_cells(const double lo[3], const double hi[3], const uint64_t first[3],
                     const uint64_t last[3], uint64_t cells, bool in_layer,
                     const SiteBlock* block) {
  const double r2 = kInclusionRadius * kInclusionRadius;
  bool some = false;
  for (uint64_t k = first[2]; k <= last[2]; ++k)
    for (uint64_t j = first[1]; j <= last[1]; ++j) {
      const uint64_t row = kFromBlock ? 0 : InclusionSite::row_hash(j, k);
      for (uint64_t i = first[0]; i <= last[0]; ++i) {
        const double* c;
        double found[3];
        if constexpr (kFromBlock) {
          const size_t s = block->at(i, j, k);
          if (!block->has[s]) continue;
          c = block->c[s];
        } else {
          const uint64_t h = InclusionSite::cell_hash(i, row);
          if (!InclusionSite::has_site(h)) continue;
          InclusionSite::centre(i, j, k, h, found);
          c = found;
        }
        double near2 = 0, far2 = 0;
        axis_distance(c[0], lo[0], hi[0], &near2, &far2);
        axis_distance(c[1], lo[1], hi[1], &near2, &far2);
        axis_distance(c[2], lo[2], hi[2], &near2, &far2);
        if (far2 < r2 * (1 - kRadiusMargin) && in_layer && cells == 1) return Reach::kAll;
        if (near2 < r2 * (1 + kRadiusMargin)) some = true;
      }
    }
  return some ? Reach::kSome : Reach::kNone;
}

// Whether the rock points of [lo, hi] may lie in an inclusion: none, some,
// or all of the box (inside one sphere, which lies inside its cell), the
// cells [first, last] the box meets known, and their sites found already
// where `block` (holding them) is not null.
Reach inclusion_reach(const double lo[3], const double hi[3], const uint64_t first[3],
                      const uint64_t last[3], const SiteBlock* block) {
  if (lo[2] >= kInclusionDepth || hi[0] < 0 || hi[1] < 0 || hi[2] < 0) return Reach::kNone;
  const bool in_layer = lo[0] >= 0 && lo[1] >= 0 && lo[2] >= 0 && hi[2] < kInclusionDepth;
  uint64_t cells = 1;
  for (int a = 0; a < 3; ++a) cells *= last[a] - first[a] + 1;
  if (cells > kMostCellsLooked) return Reach::kSome;
  return block != nullptr ? reach_of_cells<true>(lo, hi, first, last, cells, in_layer, block)
                          : reach_of_cells<false>(lo, hi, first, last, cells, in_layer, nullptr);
}

// The same, the cells found here.
Reach inclusion_reach(const double lo[3], const double hi[3]) {
  uint64_t first[3], last[3];
  for (int a = 0; a < 3; ++a) {
    first[a] = InclusionCell::index(lo[a]), last[a] = InclusionCell::index(hi[a]);
  }
  return inclusion_reach(lo, hi, first, last, nullptr);
}

}  // namespace

// The Vs of each kind of point present in the box: sediment and rock
// rise with depth (so their extremes are at the box's top and bottom),
// inclusions are kInclusionVs.  Which kinds are present comes from the
// range of the bowls' depth over the box's columns and from the spheres of
// the inclusion cells it meets, each with a margin far wider than the
// rounding of at()'s arithmetic, so that a point on a border counts as
// either kind.
void vs_bounds(const double lo[3], const double hi[3], float* vs_lo, float* vs_hi) {
  const float sediment[2] = {static_cast<float>(vs_of(lo[2], true, false)),
                             static_cast<float>(vs_of(hi[2], true, false))};
  const float rock[2] = {static_cast<float>(vs_of(lo[2], false, false)),
                         static_cast<float>(vs_of(hi[2], false, false))};
  const Span vs = vs_span(lo[2], hi[2], sediment_depth_span(lo, hi), sediment, rock,
                          [&] { return inclusion_reach(lo, hi); });
  *vs_lo = vs.lo, *vs_hi = vs.hi;
}

// The same for the eight halves of a box: the bowls' depth over each
// quarter of its columns (shared by the two halves in z), Vs at the three
// depths, the cells' indices at the three coordinates of each axis, and
// the inclusion sites of the whole box's cells, each found once.
void vs_bounds_of_eighths(const double edges[3][3], const bool want[8], float vs_lo[8],
                          float vs_hi[8]) {
  float sediment[3], rock[3];
  uint64_t index[3][3];
  for (int t = 0; t < 3; ++t) {
    sediment[t] = static_cast<float>(vs_of(edges[2][t], true, false));
    rock[t] = static_cast<float>(vs_of(edges[2][t], false, false));
    for (int a = 0; a < 3; ++a) index[a][t] = InclusionCell::index(edges[a][t]);
  }
  Span depth[4];
  bool depth_known[4] = {};
  SiteBlock block;
  int block_state = 0;  // 0: not looked for, 1: found, 2: too many cells
  for (int c = 0; c < 8; ++c) {
    if (!want[c]) continue;
    const int b[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
    double lo[3], hi[3];
    uint64_t first[3], last[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = edges[a][b[a]], hi[a] = edges[a][b[a] + 1];
      first[a] = index[a][b[a]], last[a] = index[a][b[a] + 1];
    }
    const int quarter = c & 3;
    if (!depth_known[quarter]) {
      depth[quarter] = sediment_depth_span(lo, hi), depth_known[quarter] = true;
    }
    auto reach = [&] {
      if (block_state == 0) {
        const uint64_t whole_first[3] = {index[0][0], index[1][0], index[2][0]};
        const uint64_t whole_last[3] = {index[0][2], index[1][2], index[2][2]};
        block_state = find_sites(whole_first, whole_last, &block) ? 1 : 2;
      }
      return inclusion_reach(lo, hi, first, last, block_state == 1 ? &block : nullptr);
    };
    const Span vs = vs_span(lo[2], hi[2], depth[quarter], sediment + b[2], rock + b[2], reach);
    vs_lo[c] = static_cast<float>(vs.lo), vs_hi[c] = static_cast<float>(vs.hi);
  }
}

}  // namespace weaver::basin
