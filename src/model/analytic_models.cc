// The built-in models: halfspace, LOH.1 and the synthetic basin.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include "model/grid_model.h"
#include "model/velocity_model.h"

namespace weaver {
namespace {

constexpr Material kHalfspace{6000, 3464, 2700};

class Halfspace final : public VelocityModel {
 public:
  Material at(double, double, double) const override { return kHalfspace; }
  std::string describe() const override { return "halfspace: Vp 6000, Vs 3464, rho 2700"; }
};

// SCEC LOH.1: a 1000 m layer over the half-space.
class Loh1 final : public VelocityModel {
 public:
  Material at(double, double, double z) const override {
    return z < kLayerDepth ? Material{4000, 2000, 2600} : kHalfspace;
  }
  std::string describe() const override {
    return "loh1: 1000 m layer (Vp 4000, Vs 2000, rho 2600) over the half-space";
  }

 private:
  static constexpr double kLayerDepth = 1000;
};

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
    const bool sediment = z < sediment_depth(x, y);
    const double vs = vs_at(x, y, z, sediment);
    // Poisson-solid-like Vp for rock, a water-saturated floor for sediments
    // and inclusions; Gardner-like density.
    const double vp = std::max(1500.0, vs * (sediment ? 2.0 : std::sqrt(3.0)));
    const double rho = 1700 + 0.29 * vs;
    return {static_cast<float>(vp), static_cast<float>(vs), static_cast<float>(rho)};
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

  static double vs_at(double x, double y, double z, bool sediment) {
    return vs_of(z, sediment, !sediment && InclusionCell().holds(x, y, z));
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
    static uint64_t index(double v) {
      return v < 0 ? 0 : static_cast<uint64_t>(v / kInclusionCell);
    }

   private:
    void locate(uint64_t i, uint64_t j, uint64_t k) {
      known_ = true;
      i_ = i, j_ = j, k_ = k;
      const uint64_t h = mix(i * 0x100000001b3ull ^ mix(j * 0x2545f491ull ^ mix(k)));
      has_ = (h & 0xffff) < kInclusionShare * 65536;
      const double span = (kInclusionCell - 2 * kInclusionRadius) / 65536;
      cx_ = i * kInclusionCell + kInclusionRadius + span * ((h >> 16) & 0xffff);
      cy_ = j * kInclusionCell + kInclusionRadius + span * ((h >> 32) & 0xffff);
      cz_ = k * kInclusionCell + kInclusionRadius + span * ((h >> 48) & 0xffff);
    }

    // The cell index along each axis of the last coordinate seen there (a
    // lattice repeats its coordinates).
    struct Axes {
      uint64_t cell(int a, double v) {
        if (v != at[a]) at[a] = v, index[a] = InclusionCell::index(v);
        return index[a];
      }
      double at[3] = {-1, -1, -1};
      uint64_t index[3] = {};
    };

    Axes axis_;
    bool known_ = false, has_ = false;
    uint64_t i_ = 0, j_ = 0, k_ = 0;
    double cx_ = 0, cy_ = 0, cz_ = 0;
  };
};

}  // namespace

Status make_model(const std::string& name, const std::string& grid_file,
                  std::unique_ptr<VelocityModel>* out) {
  if (name == "halfspace") {
    *out = std::make_unique<Halfspace>();
  } else if (name == "loh1") {
    *out = std::make_unique<Loh1>();
  } else if (name == "basin") {
    *out = std::make_unique<Basin>();
  } else if (name == "grid") {
    if (grid_file.empty()) return Status::InvalidArgument("model grid needs a FILE");
    return load_grid_model(grid_file, out);
  } else {
    return Status::InvalidArgument("unknown model '" + name +
                                   "' (halfspace, loh1, basin or grid FILE)");
  }
  return Status::Ok();
}

}  // namespace weaver
