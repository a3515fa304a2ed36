#include "model/basin_model.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include "util/truncated_quotient.h"

namespace weaver {
namespace {

// A synthetic sedimentary basin standing in for the SCEC model of the Los
// Angeles basin used by the paper: soft sediments in smooth bowls, Vs rising
// with depth, over and beside stiffer rock whose Vs also rises with depth.
//
// Smooth material alone cannot reproduce the paper's growth of about 11x per
// doubling of frequency: with exact minima each leaf of the f mesh becomes at
// most 8 leaves of the 2f mesh.  The real model has small-scale structure
// that only fine sampling sees, so the rock near the surface holds small soft
// inclusions (radius 40 m, Vs 100 m/s), one in every fourth 600 m cell at a
// hashed position.  A coarse leaf's 27 samples rarely hit one; at 1-2 Hz most
// are found and each costs thousands of small elements.  Parameters are
// calibrated so that meshes at 10 points per wavelength land near the element
// counts of the paper's Figure 11 (see bench/mesh_bench).
class Basin final : public VelocityModel {
 public:
  Material at(double x, double y, double z) const override {
    return material_of(z, sediment_depth(x, y), x, y, inclusion_cell());
  }
  // The bowl depth once per column; the materials of sediment and of rock
  // once per depth (they follow from Vs, which follows from the depth), and
  // the inclusion cell's index once per coordinate; then each point takes
  // one of three.  The values are at()'s, to the bit.
  void materials_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                            Material* out) const override {
    if (n > kLatticeMax) return VelocityModel::materials_on_lattice(xs, ys, zs, n, out);
    // Storage assigned whole below, not Materials zeroed first (a fifth of
    // the function).
    alignas(Material) unsigned char storage[2 * kLatticeMax * sizeof(Material)];
    Material* sediment = reinterpret_cast<Material*>(storage);
    Material* rock = sediment + kLatticeMax;
    uint64_t cell_of[3][kLatticeMax];
    const double* axes[3] = {xs, ys, zs};
    for (int k = 0; k < n; ++k) {
      sediment[k] = material_for(vs_of(zs[k], true, false), true);
      rock[k] = material_for(vs_of(zs[k], false, false), false);
    }
    for (int a = 0; a < 3; ++a) {
      for (int i = 0; i < n; ++i) cell_of[a][i] = InclusionCell::index(axes[a][i]);
    }
    const Material inclusion = material_for(vs_of(0, false, true), false);
    InclusionCell& cell = inclusion_cell();
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const double depth = sediment_depth(xs[i], ys[j]);
        const bool may_hold = xs[i] >= 0 && ys[j] >= 0;
        for (int k = 0; k < n; ++k) {
          const Material* m = &rock[k];
          if (zs[k] < depth) {
            m = &sediment[k];
          } else if (may_hold && zs[k] >= 0 && zs[k] < kInclusionDepth &&
                     cell.holds_in(cell_of[0][i], cell_of[1][j], cell_of[2][k], xs[i], ys[j],
                                   zs[k])) {
            m = &inclusion;
          }
          out[(k * n + j) * n + i] = *m;
        }
      }
    }
  }
  // The bowl depth once per column of the lattice; Vs of sediment and of
  // rock, and the inclusion cell's index, once per depth; an inclusion
  // cell's hash once per run of points in the same cell (a small octant's
  // points share one); Vs only.  The values are at()'s, to the bit.
  void vs_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                     float* out) const override {
    if (n > kLatticeMax) return VelocityModel::vs_on_lattice(xs, ys, zs, n, out);
    float sediment_vs[kLatticeMax], rock_vs[kLatticeMax];
    uint64_t cell_of[3][kLatticeMax];
    const double* axes[3] = {xs, ys, zs};
    for (int k = 0; k < n; ++k) {
      sediment_vs[k] = static_cast<float>(vs_of(zs[k], true, false));
      rock_vs[k] = static_cast<float>(vs_of(zs[k], false, false));
    }
    for (int a = 0; a < 3; ++a) {
      for (int i = 0; i < n; ++i) cell_of[a][i] = InclusionCell::index(axes[a][i]);
    }
    InclusionCell cell;
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const double depth = sediment_depth(xs[i], ys[j]);
        const bool may_hold = xs[i] >= 0 && ys[j] >= 0;
        for (int k = 0; k < n; ++k) {
          float vs = rock_vs[k];
          if (zs[k] < depth) {
            vs = sediment_vs[k];
          } else if (may_hold && zs[k] >= 0 && zs[k] < kInclusionDepth &&
                     cell.holds_in(cell_of[0][i], cell_of[1][j], cell_of[2][k], xs[i], ys[j],
                                   zs[k])) {
            vs = static_cast<float>(kInclusionVs);
          }
          out[(k * n + j) * n + i] = vs;
        }
      }
    }
  }

  // Columns of their own depths (a model under a ground): the bowl depth
  // once per column, the rest per point as at().
  void materials_on_columns(const double* xs, const double* ys, const double* zs, int n,
                            Material* out) const override {
    InclusionCell& cell = inclusion_cell();
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const double depth = sediment_depth(xs[i], ys[j]);
        const double* z = zs + (j * n + i) * n;
        for (int k = 0; k < n; ++k) {
          out[(k * n + j) * n + i] = material_of(z[k], depth, xs[i], ys[j], cell);
        }
      }
    }
  }
  // The bowl depth once per column, Vs per point as at() rounds it; the
  // inclusion cells' indices along x and y once per lattice.
  void vs_on_columns(const double* xs, const double* ys, const double* zs, int n,
                     float* out) const override {
    if (n > kLatticeMax) return VelocityModel::vs_on_columns(xs, ys, zs, n, out);
    uint64_t cell_x[kLatticeMax], cell_y[kLatticeMax];
    for (int i = 0; i < n; ++i) {
      cell_x[i] = InclusionCell::index(xs[i]), cell_y[i] = InclusionCell::index(ys[i]);
    }
    InclusionCell cell;
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const double depth = sediment_depth(xs[i], ys[j]);
        const bool may_hold = xs[i] >= 0 && ys[j] >= 0;
        const double* z = zs + (j * n + i) * n;
        for (int k = 0; k < n; ++k) {
          const bool sediment = z[k] < depth;
          const bool inclusion =
              !sediment && may_hold && z[k] >= 0 && z[k] < kInclusionDepth &&
              cell.holds_in(cell_x[i], cell_y[j], InclusionCell::index(z[k]), xs[i], ys[j], z[k]);
          out[(k * n + j) * n + i] = static_cast<float>(vs_of(z[k], sediment, inclusion));
        }
      }
    }
  }

  // The Vs of each kind of point present in the box: sediment and rock
  // rise with depth (so their extremes are at the box's top and bottom),
  // inclusions are kInclusionVs.  Which kinds are present comes from the
  // range of the bowls' depth over the box's columns and from the spheres of
  // the inclusion cells it meets, each with a margin far wider than the
  // rounding of at()'s arithmetic, so that a point on a border counts as
  // either kind.
  bool vs_bounds(const double lo[3], const double hi[3], float* vs_lo,
                 float* vs_hi) const override {
    const float sediment[2] = {static_cast<float>(vs_of(lo[2], true, false)),
                               static_cast<float>(vs_of(hi[2], true, false))};
    const float rock[2] = {static_cast<float>(vs_of(lo[2], false, false)),
                           static_cast<float>(vs_of(hi[2], false, false))};
    const Span vs = vs_span(lo[2], hi[2], sediment_depth_span(lo, hi), sediment, rock,
                            [&] { return inclusion_reach(lo, hi); });
    *vs_lo = vs.lo, *vs_hi = vs.hi;
    return true;
  }
  // The same for the eight halves of a box: the bowls' depth over each
  // quarter of its columns (shared by the two halves in z), Vs at the three
  // depths, the cells' indices at the three coordinates of each axis, and
  // the inclusion sites of the whole box's cells, each found once.
  void vs_bounds_of_eighths(const double edges[3][3], const bool want[8], float vs_lo[8],
                            float vs_hi[8], bool ok[8]) const override {
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
      vs_lo[c] = static_cast<float>(vs.lo), vs_hi[c] = static_cast<float>(vs.hi), ok[c] = true;
    }
  }

  std::string describe() const override {
    char buf[300];
    std::snprintf(buf, sizeof buf,
                  "basin: %d bowls of sediment (Vs %.0f + %.2f/s x depth) in rock (Vs %.0f + "
                  "%.3f/s x depth, at most %.0f) with soft inclusions (Vs %.0f, radius %.0f m, "
                  "1 per %.0f 600 m cells, above %.0f m)",
                  kBowlCount, kSedimentVs0, kSedimentGradient, kRockVs0, kRockGradient, kRockVsMax,
                  kInclusionVs, kInclusionRadius, 1 / kInclusionShare, kInclusionDepth);
    return buf;
  }

 private:
  struct Bowl {
    double cx, cy, radius, depth;  // metres
  };
  static constexpr int kBowlCount = 3;
  static constexpr Bowl kBowls[kBowlCount] = {
      {42000, 55000, 26000, 6000}, {72000, 33000, 15000, 3500}, {22000, 24000, 11000, 2000}};
  static constexpr double kSedimentVs0 = 575, kSedimentGradient = 0.75;
  static constexpr double kRockVs0 = 2600, kRockGradient = 0.2, kRockVsMax = 3900;
  static constexpr double kInclusionVs = 100, kInclusionRadius = 40;
  static constexpr double kInclusionCell = 600, kInclusionShare = 0.25, kInclusionDepth = 5000;
  static constexpr int kLatticeMax = 8;

  // A closed interval, empty until something is added.
  struct Span {
    double lo = HUGE_VAL, hi = -HUGE_VAL;
    void add(double v) { lo = std::min(lo, v), hi = std::max(hi, v); }
  };
  // Wider than any rounding of the arithmetic below (metres; m^2 relative).
  static constexpr double kDepthMargin = 1e-6, kRadiusMargin = 1e-9;

  // The least and greatest squared distance from c to the points of [lo, hi]
  // along one axis.
  static void axis_distance(double c, double lo, double hi, double* near2, double* far2) {
    const double near = std::max({lo - c, c - hi, 0.0});
    const double far = std::max(std::abs(lo - c), std::abs(hi - c));
    *near2 += near * near, *far2 += far * far;
  }

  // Bounds on sediment_depth over the columns of the box [lo, hi]: a bowl's
  // dish deepens towards its centre, so its extremes over the rectangle are
  // at the nearest and farthest points; the floor is the deepest bowl.
  static Span sediment_depth_span(const double lo[3], const double hi[3]) {
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
  static constexpr uint64_t kMostCellsLooked = 27;

  // The Vs of each kind of point the box [z_lo, z_hi] in depth may hold,
  // over columns whose bowls' depth lies in `depth`: sediment[0..1] and
  // rock[0..1] are each kind's Vs at z_lo and z_hi; reach() says whether
  // its rock points may lie in an inclusion.
  template <class ReachOf>
  static Span vs_span(double z_lo, double z_hi, const Span& depth, const float* sediment,
                      const float* rock, const ReachOf& reach) {
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
  static bool find_sites(const uint64_t first[3], const uint64_t last[3], SiteBlock* b) {
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

  // Whether the rock points of [lo, hi] may lie in an inclusion: none, some,
  // or all of the box (inside one sphere, which lies inside its cell).
  static Reach inclusion_reach(const double lo[3], const double hi[3]) {
    uint64_t first[3], last[3];
    for (int a = 0; a < 3; ++a) {
      first[a] = InclusionCell::index(lo[a]), last[a] = InclusionCell::index(hi[a]);
    }
    return inclusion_reach(lo, hi, first, last, nullptr);
  }
  // The same, the cells [first, last] the box meets known, and their sites
  // found already where `block` (holding them) is not null.
  static Reach inclusion_reach(const double lo[3], const double hi[3], const uint64_t first[3],
                               const uint64_t last[3], const SiteBlock* block) {
    if (lo[2] >= kInclusionDepth || hi[0] < 0 || hi[1] < 0 || hi[2] < 0) return Reach::kNone;
    const bool in_layer = lo[0] >= 0 && lo[1] >= 0 && lo[2] >= 0 && hi[2] < kInclusionDepth;
    uint64_t cells = 1;
    for (int a = 0; a < 3; ++a) cells *= last[a] - first[a] + 1;
    if (cells > kMostCellsLooked) return Reach::kSome;
    SiteBlock own;
    if (block == nullptr) find_sites(first, last, &own), block = &own;
    const double r2 = kInclusionRadius * kInclusionRadius;
    bool some = false;
    for (uint64_t k = first[2]; k <= last[2]; ++k)
      for (uint64_t j = first[1]; j <= last[1]; ++j)
        for (uint64_t i = first[0]; i <= last[0]; ++i) {
          const size_t s = block->at(i, j, k);
          if (!block->has[s]) continue;
          double near2 = 0, far2 = 0;
          axis_distance(block->c[s][0], lo[0], hi[0], &near2, &far2);
          axis_distance(block->c[s][1], lo[1], hi[1], &near2, &far2);
          axis_distance(block->c[s][2], lo[2], hi[2], &near2, &far2);
          if (far2 < r2 * (1 - kRadiusMargin) && in_layer && cells == 1) return Reach::kAll;
          if (near2 < r2 * (1 + kRadiusMargin)) some = true;
        }
    return some ? Reach::kSome : Reach::kNone;
  }

  class InclusionCell;
  // The material at (x, y, z), under a sediment floor at depth.
  static Material material_of(double z, double depth, double x, double y, InclusionCell& cell) {
    const bool sediment = z < depth;
    return material_for(vs_of(z, sediment, !sediment && cell.holds(x, y, z)), sediment);
  }
  // Poisson-solid-like Vp for rock, a water-saturated floor for sediments
  // and inclusions; Gardner-like density.
  static Material material_for(double vs, bool sediment) {
    const double vp = std::max(1500.0, vs * (sediment ? 2.0 : std::sqrt(3.0)));
    const double rho = 1700 + 0.29 * vs;
    return {static_cast<float>(vp), static_cast<float>(vs), static_cast<float>(rho)};
  }
  // Each thread's cell for at(): leaves come in Z-order, so most follow one
  // in the same 600 m cell, whose hash is most of at()'s cost.  (The answer
  // is the same either way.)
  static InclusionCell& inclusion_cell() {
    thread_local InclusionCell cell;
    return cell;
  }
  static double vs_of(double z, bool sediment, bool inclusion) {
    if (inclusion) return kInclusionVs;
    const double vs =
        sediment ? kSedimentVs0 + kSedimentGradient * z : kRockVs0 + kRockGradient * z;
    return std::min(vs, kRockVsMax);
  }

  // Depth of the sediment floor at (x, y): the deepest bowl there; each bowl
  // is a smooth quartic dish, zero at its rim.
  static double sediment_depth(double x, double y) {
    double d = 0;
    for (const Bowl& b : kBowls) {
      const double dx = x - b.cx, dy = y - b.cy, r2 = b.radius * b.radius;
      if (dx * dx + dy * dy >= r2) continue;  // outside the rim: q >= 1, no division
      const double q = (dx * dx + dy * dy) / r2;
      if (q < 1) d = std::max(d, b.depth * (1 - q) * (1 - q));
    }
    return d;
  }

  static uint64_t mix(uint64_t v) {  // splitmix64's finaliser
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
      centre(i, j, k, h, s.c);
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
};

}  // namespace

std::unique_ptr<VelocityModel> make_basin_model() { return std::make_unique<Basin>(); }

}  // namespace weaver
