// The built-in models: halfspace, LOH.1 and the synthetic basin.
#include <algorithm>
#include <cmath>
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
// Parameters are calibrated so that meshes at 10 points per wavelength land
// near the element counts of the paper's Figure 11 (see the bench).
class Basin final : public VelocityModel {
 public:
  Material at(double x, double y, double z) const override {
    const double depth = sediment_depth(x, y);
    double vs;
    if (z < depth) {
      vs = kSedimentVs0 + kSedimentGradient * z;
    } else {
      vs = std::min(kRockVsMax, kRockVs0 + kRockGradient * z);
    }
    vs = std::min(vs, kRockVsMax);
    // Poisson-solid-like Vp for rock, a water-saturated floor for sediments;
    // Gardner-like density.
    const double vp = std::max(1500.0, vs * (z < depth ? 2.0 : std::sqrt(3.0)));
    const double rho = 1700 + 0.29 * vs;
    return {static_cast<float>(vp), static_cast<float>(vs), static_cast<float>(rho)};
  }
  std::string describe() const override {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "basin: %d bowls of sediment (Vs %.0f + %.2f/s x depth) in rock (Vs %.0f + "
                  "%.3f/s x depth, at most %.0f)",
                  kBowlCount, kSedimentVs0, kSedimentGradient, kRockVs0, kRockGradient,
                  kRockVsMax);
    return buf;
  }

 private:
  struct Bowl {
    double cx, cy, radius, depth;  // metres
  };
  static constexpr int kBowlCount = 3;
  static constexpr Bowl kBowls[kBowlCount] = {{42000, 55000, 26000, 6000},
                                              {72000, 33000, 15000, 3500},
                                              {22000, 24000, 11000, 2000}};
  static constexpr double kSedimentVs0 = 450, kSedimentGradient = 0.55;
  static constexpr double kRockVs0 = 2500, kRockGradient = 0.2, kRockVsMax = 3464;

  // Depth of the sediment floor at (x, y): the deepest bowl there; each bowl
  // is a smooth quartic dish, zero at its rim.
  static double sediment_depth(double x, double y) {
    double d = 0;
    for (const Bowl& b : kBowls) {
      const double dx = x - b.cx, dy = y - b.cy;
      const double q = (dx * dx + dy * dy) / (b.radius * b.radius);
      if (q < 1) d = std::max(d, b.depth * (1 - q) * (1 - q));
    }
    return d;
  }
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
