#include "model/basin_model.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include "model/basin_bounds.h"
#include "model/basin_shape.h"

namespace weaver {
namespace {

using namespace basin;

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
    for (int k = 0; k < n; ++k) {
      sediment[k] = material_for(vs_of(zs[k], true, false), true);
      rock[k] = material_for(vs_of(zs[k], false, false), false);
    }
    const Material inclusion = material_for(vs_of(0, false, true), false);
    pick_on_lattice(xs, ys, zs, n, sediment, rock, inclusion, inclusion_cell(), out);
  }
  // The same with Vs only; an inclusion cell's hash once per run of points
  // in the same cell (a small octant's points share one).
  void vs_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                     float* out) const override {
    if (n > kLatticeMax) return VelocityModel::vs_on_lattice(xs, ys, zs, n, out);
    float sediment[kLatticeMax], rock[kLatticeMax];
    for (int k = 0; k < n; ++k) {
      sediment[k] = static_cast<float>(vs_of(zs[k], true, false));
      rock[k] = static_cast<float>(vs_of(zs[k], false, false));
    }
    InclusionCell cell;
    pick_on_lattice(xs, ys, zs, n, sediment, rock, static_cast<float>(kInclusionVs), cell, out);
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

  bool vs_bounds(const double lo[3], const double hi[3], float* vs_lo,
                 float* vs_hi) const override {
    basin::vs_bounds(lo, hi, vs_lo, vs_hi);
    return true;
  }
  void vs_bounds_of_eighths(const double edges[3][3], const bool want[8], float vs_lo[8],
                            float vs_hi[8], bool ok[8]) const override {
    basin::vs_bounds_of_eighths(edges, want, vs_lo, vs_hi);
    for (int c = 0; c < 8; ++c) ok[c] = want[c];
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
  static constexpr int kLatticeMax = 8;

  // Each point (xs[i], ys[j], zs[k]) of an n x n x n lattice (n at most
  // kLatticeMax) takes the value of its kind, as at() finds it: sediment[k]
  // above its column's bowl floor, `inclusion` inside an inclusion, else
  // rock[k]; into out[(k * n + j) * n + i].  The bowl depth once per
  // column, the inclusion cells' indices once per coordinate; and where the
  // lattice lies in one cell (a small octant's) its site once, or where it
  // lies outside the inclusions' layer none at all.
  template <class T>
  static void pick_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                              const T* sediment, const T* rock, const T& inclusion,
                              InclusionCell& cell, T* out) {
    double depth[kLatticeMax * kLatticeMax];
    column_depths(xs, ys, n, depth);
    bool in_layer[3][kLatticeMax];  // x, y >= 0; 0 <= z < kInclusionDepth
    bool any[3] = {};
    const double* axes[3] = {xs, ys, zs};
    for (int a = 0; a < 3; ++a) {
      for (int i = 0; i < n; ++i) {
        const double v = axes[a][i];
        in_layer[a][i] = v >= 0 && (a < 2 || v < kInclusionDepth);
        any[a] |= in_layer[a][i];
      }
    }
    if (!(any[0] && any[1] && any[2])) {
      pick_without_inclusions(zs, n, depth, sediment, rock, out);
      return;
    }
    uint64_t cell_of[3][kLatticeMax];
    bool one_cell = true;
    for (int a = 0; a < 3; ++a) {
      for (int i = 0; i < n; ++i) {
        cell_of[a][i] = InclusionCell::index(axes[a][i]);
        one_cell = one_cell && cell_of[a][i] == cell_of[a][0];
      }
    }
    double centre[3];
    if (one_cell && !cell.site_of(cell_of[0][0], cell_of[1][0], cell_of[2][0], centre)) {
      pick_without_inclusions(zs, n, depth, sediment, rock, out);
      return;
    }
    if (one_cell) {
      // All points in one cell, its inclusion centred at `centre`: the
      // sphere's test from each axis's squared distances, summed as
      // InclusionCell::holds_in sums them.
      double square[3][kLatticeMax];
      for (int a = 0; a < 3; ++a) {
        for (int i = 0; i < n; ++i) {
          const double d = axes[a][i] - centre[a];
          square[a][i] = d * d;
        }
      }
      // (A column whose own part reaches r holds no point of it.)
      constexpr double r2 = kInclusionRadius * kInclusionRadius;
      pick_each(
          zs, n, depth, sediment, rock, inclusion, out,
          [&](int i, int j) {
            return in_layer[0][i] && in_layer[1][j] && square[0][i] + square[1][j] < r2;
          },
          [&](int i, int j, int k) {
            return in_layer[2][k] && square[0][i] + square[1][j] + square[2][k] < r2;
          });
      return;
    }
    pick_each(
        zs, n, depth, sediment, rock, inclusion, out,
        [&](int i, int j) { return in_layer[0][i] && in_layer[1][j]; },
        [&](int i, int j, int k) {
          return in_layer[2][k] &&
                 cell.holds_in(cell_of[0][i], cell_of[1][j], cell_of[2][k], xs[i], ys[j], zs[k]);
        });
  }
  // Sediment above each column's bowl floor, rock below it: no point of
  // the lattice can be in an inclusion.
  template <class T>
  static void pick_without_inclusions(const double* zs, int n, const double* depth,
                                      const T* sediment, const T* rock, T* out) {
    for (int k = 0; k < n; ++k) {
      for (int c = 0; c < n * n; ++c) out[k * n * n + c] = zs[k] < depth[c] ? sediment[k] : rock[k];
    }
  }
  // Each point sediment above its column's bowl floor, else `inclusion`
  // where its column may hold one (column(i, j)) and it does (point(i, j,
  // k)), else rock.
  template <class T, class Column, class Point>
  static void pick_each(const double* zs, int n, const double* depth, const T* sediment,
                        const T* rock, const T& inclusion, T* out, const Column& column,
                        const Point& point) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const double d = depth[j * n + i];
        const bool may_hold = column(i, j);
        for (int k = 0; k < n; ++k) {
          const T* v = &rock[k];
          if (zs[k] < d) {
            v = &sediment[k];
          } else if (may_hold && point(i, j, k)) {
            v = &inclusion;
          }
          out[(k * n + j) * n + i] = *v;
        }
      }
    }
  }
  // The material at (x, y, z), under a sediment floor at depth.
  static Material material_of(double z, double depth, double x, double y, InclusionCell& cell) {
    const bool sediment = z < depth;
    return material_for(vs_of(z, sediment, !sediment && cell.holds(x, y, z)), sediment);
  }
  // Each thread's cell for at(): leaves come in Z-order, so most follow one
  // in the same 600 m cell, whose hash is most of at()'s cost.  (The answer
  // is the same either way.)
  static InclusionCell& inclusion_cell() {
    thread_local InclusionCell cell;
    return cell;
  }
};

}  // namespace

std::unique_ptr<VelocityModel> make_basin_model() { return std::make_unique<Basin>(); }

}  // namespace weaver
