// The built-in models: halfspace, LOH.1 and the synthetic basin.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>

#include "model/basin_model.h"
#include "model/grid_model.h"
#include "model/velocity_model.h"

namespace weaver {
namespace {

constexpr Material kHalfspace{6000, 3464, 2700};

class Halfspace final : public VelocityModel {
 public:
  Material at(double, double, double) const override { return kHalfspace; }
  bool vs_bounds(const double*, const double*, float* vs_lo, float* vs_hi) const override {
    *vs_lo = *vs_hi = kHalfspace.vs;
    return true;
  }
  std::string describe() const override { return "halfspace: Vp 6000, Vs 3464, rho 2700"; }
};

// SCEC LOH.1: a 1000 m layer over the half-space.
class Loh1 final : public VelocityModel {
 public:
  Material at(double, double, double z) const override {
    return z < kLayerDepth ? Material{4000, 2000, 2600} : kHalfspace;
  }
  bool vs_bounds(const double lo[3], const double hi[3], float* vs_lo,
                 float* vs_hi) const override {
    *vs_lo = at(0, 0, lo[2]).vs, *vs_hi = at(0, 0, hi[2]).vs;
    if (*vs_lo > *vs_hi) std::swap(*vs_lo, *vs_hi);
    return true;
  }
  std::string describe() const override {
    return "loh1: 1000 m layer (Vp 4000, Vs 2000, rho 2600) over the half-space";
  }

 private:
  static constexpr double kLayerDepth = 1000;
};

}  // namespace

Status make_model(const std::string& name, const std::string& grid_file,
                  std::unique_ptr<VelocityModel>* out) {
  if (name == "halfspace") {
    *out = std::make_unique<Halfspace>();
  } else if (name == "loh1") {
    *out = std::make_unique<Loh1>();
  } else if (name == "basin") {
    *out = make_basin_model();
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
