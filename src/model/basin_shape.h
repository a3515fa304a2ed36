// The synthetic basin's shape (basin_model.cc describes it): its bowls of
// sediment, the Vs of each kind of point, and the inclusion cells, shared by
// its samples (basin_model.cc) and its bounds (basin_bounds.cc).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "model/velocity_model.h"
#include "util/truncated_quotient.h"

namespace weaver::basin {

struct Bowl {
  double cx, cy, radius, depth;  // metres
};
inline constexpr int kBowlCount = 3;
inline constexpr Bowl kBowls[kBowlCount] = {
    {42000, 55000, 26000, 6000}, {72000, 33000, 15000, 3500}, {22000, 24000, 11000, 2000}};
inline constexpr double kSedimentVs0 = 575, kSedimentGradient = 0.75;
inline constexpr double kRockVs0 = 2600, kRockGradient = 0.2, kRockVsMax = 3900;
inline constexpr double kInclusionVs = 100, kInclusionRadius = 40;
inline constexpr double kInclusionCell = 600, kInclusionShare = 0.25, kInclusionDepth = 5000;

// Poisson-solid-like Vp for rock, a water-saturated floor for sediments
// and inclusions; Gardner-like density.
inline Material material_for(double vs, bool sediment) {
  const double vp = std::max(1500.0, vs * (sediment ? 2.0 : std::sqrt(3.0)));
  const double rho = 1700 + 0.29 * vs;
  return {static_cast<float>(vp), static_cast<float>(vs), static_cast<float>(rho)};
}

inline double vs_of(double z, bool sediment, bool inclusion) {
  if (inclusion) return kInclusionVs;
  const double vs = sediment ? kSedimentVs0 + kSedimentGradient * z : kRockVs0 + kRockGradient * z;
  return std::min(vs, kRockVsMax);
}

// Depth of the sediment floor at (x, y) under `count` bowls: the deepest
// there; each bowl is a smooth quartic dish, zero at its rim.
inline double deepest_bowl(const Bowl* bowls, int count, double x, double y) {
  double d = 0;
  for (int i = 0; i < count; ++i) {
    const Bowl& b = bowls[i];
    const double dx = x - b.cx, dy = y - b.cy, r2 = b.radius * b.radius;
    if (dx * dx + dy * dy >= r2) continue;  // outside the rim: q >= 1, no division
    const double q = (dx * dx + dy * dy) / r2;
    if (q < 1) d = std::max(d, b.depth * (1 - q) * (1 - q));
  }
  return d;
}

// Depth of the sediment floor at (x, y).
inline double sediment_depth(double x, double y) { return deepest_bowl(kBowls, kBowlCount, x, y); }

// sediment_depth at each column (xs[i], ys[j]) of an n x n lattice, into
// depth[j * n + i]; a bowl whose rim the lattice's columns all lie outside
// is not looked at (its nearest point to them is at r or more, so each
// column's own distance is too, rounding being monotone): the same values.
inline void column_depths(const double* xs, const double* ys, int n, double* depth) {
  const auto [x_lo, x_hi] = std::minmax_element(xs, xs + n);
  const auto [y_lo, y_hi] = std::minmax_element(ys, ys + n);
  Bowl near[kBowlCount];
  int count = 0;
  for (const Bowl& b : kBowls) {
    const double dx = std::clamp(b.cx, *x_lo, *x_hi) - b.cx;
    const double dy = std::clamp(b.cy, *y_lo, *y_hi) - b.cy;
    if (dx * dx + dy * dy < b.radius * b.radius) near[count++] = b;
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) depth[j * n + i] = deepest_bowl(near, count, xs[i], ys[j]);
  }
}

inline uint64_t mix(uint64_t v) {  // splitmix64's finaliser
  v += 0x9e3779b97f4a7c15ull;
  v = (v ^ (v >> 30)) * 0xbf58476d1ce4e5b9ull;
  v = (v ^ (v >> 27)) * 0x94d049bb133111ebull;
  return v ^ (v >> 31);
}

// Whether cell (i, j, k) holds an inclusion, and its centre.
// The hash is a chain, k's mixed first: a row of cells along x shares
// the mix of its (j, k) (row_hash), and only a cell that has an
// inclusion needs its centre.
struct InclusionSite {
  bool has;
  double c[3];
  static uint64_t row_hash(uint64_t j, uint64_t k) { return mix(j * 0x2545f491ull ^ mix(k)); }
  static uint64_t cell_hash(uint64_t i, uint64_t row) { return mix(i * 0x100000001b3ull ^ row); }
  static bool has_site(uint64_t h) { return (h & 0xffff) < kInclusionShare * 65536; }
  static void centre(uint64_t i, uint64_t j, uint64_t k, uint64_t h, double* c) {
    const double span = (kInclusionCell - 2 * kInclusionRadius) / 65536;
    c[0] = i * kInclusionCell + kInclusionRadius + span * ((h >> 16) & 0xffff);
    c[1] = j * kInclusionCell + kInclusionRadius + span * ((h >> 32) & 0xffff);
    c[2] = k * kInclusionCell + kInclusionRadius + span * ((h >> 48) & 0xffff);
  }
  static InclusionSite of(uint64_t i, uint64_t j, uint64_t k) {
    const uint64_t h = cell_hash(i, row_hash(j, k));
    InclusionSite s{has_site(h), {}};
    if (s.has) centre(i, j, k, h, s.c);  // (three of four cells have none)
    return s;
  }
};

// Each cell of a 600 m lattice holds an inclusion with probability
// kInclusionShare, centred at a hashed point far enough inside the cell
// that only the cell containing a point needs checking.  The last cell
// asked about is remembered: its hash is most of the cost.
class InclusionCell {
 public:
  bool holds(double x, double y, double z) {
    if (z >= kInclusionDepth || x < 0 || y < 0 || z < 0) return false;
    return holds_in(axis_.cell(0, x), axis_.cell(1, y), axis_.cell(2, z), x, y, z);
  }
  // The same for a point whose cell (i, j, k) is known; REQUIRES: the
  // point is inside the inclusions' layer (what holds() checks first).
  bool holds_in(uint64_t i, uint64_t j, uint64_t k, double x, double y, double z) {
    if (!known_ || i != i_ || j != j_ || k != k_) locate(i, j, k);
    if (!has_) return false;
    const double dx = x - cx_, dy = y - cy_, dz = z - cz_;
    return dx * dx + dy * dy + dz * dz < kInclusionRadius * kInclusionRadius;
  }
  // Whether cell (i, j, k) has an inclusion, and then its centre into c
  // (the last cell asked is remembered, as for holds_in).
  bool site_of(uint64_t i, uint64_t j, uint64_t k, double c[3]) {
    if (!known_ || i != i_ || j != j_ || k != k_) locate(i, j, k);
    c[0] = cx_, c[1] = cy_, c[2] = cz_;
    return has_;
  }
  // (A product, not a division: a division was a twentieth of the
  // lattices' time.)
  static uint64_t index(double v) { return truncated_quotient(v, kInclusionCell); }

 private:
  void locate(uint64_t i, uint64_t j, uint64_t k) {
    known_ = true;
    i_ = i, j_ = j, k_ = k;
    const InclusionSite s = InclusionSite::of(i, j, k);
    has_ = s.has;
    cx_ = s.c[0], cy_ = s.c[1], cz_ = s.c[2];
  }

  // The cell index along each axis of the last coordinate seen there.  A
  // coordinate well inside the same cell (by far more than the rounding
  // of v / kInclusionCell) has the same index without the division.
  struct Axes {
    uint64_t cell(int a, double v) {
      if (v > inner_lo[a] && v < inner_hi[a]) return index[a];
      index[a] = InclusionCell::index(v);
      const double start = double(index[a]) * kInclusionCell;
      inner_lo[a] = v < 0 ? -HUGE_VAL : start + kCellMargin;
      inner_hi[a] = v < 0 ? 0.0 : start + kInclusionCell - kCellMargin;
      return index[a];
    }
    static constexpr double kCellMargin = 1e-6;
    double inner_lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, inner_hi[3] = {};
    uint64_t index[3] = {};
  };

  Axes axis_;
  bool known_ = false, has_ = false;
  uint64_t i_ = 0, j_ = 0, k_ = 0;
  double cx_ = 0, cy_ = 0, cz_ = 0;
};

}  // namespace weaver::basin
