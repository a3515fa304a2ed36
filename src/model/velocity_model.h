// Seismic velocity models: P and S wave speeds and density at a point.
// Coordinates are metres from the domain origin: x and y horizontal, z depth
// (positive down).
#pragma once

#include <algorithm>
#include <memory>
#include <string>

#include "schema/status.h"

namespace weaver {

struct Material {
  float vp = 0, vs = 0, rho = 0;  // m/s, m/s, kg/m^3
};

class VelocityModel {
 public:
  virtual ~VelocityModel() = default;
  virtual Material at(double x, double y, double z) const = 0;
  // The least Vs over the 3 x 3 x 3 lattice (x + i h, y + j h, z + k h),
  // i, j, k in 0..2: what construct asks of every octant it visits.  Models
  // override it when they can share work between the samples.
  virtual double min_vs_on_lattice(double x, double y, double z, double h) const {
    double vs = 1e300;
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i)
          vs = std::min<double>(vs, at(x + i * h, y + j * h, z + k * h).vs);
    return vs;
  }
  // A one-line description with the parameters, for logs and metadata.
  virtual std::string describe() const = 0;
};

// "halfspace", "loh1", "basin", or "grid" (with grid_file).  InvalidArgument
// for an unknown name; grid file errors name the file.
Status make_model(const std::string& name, const std::string& grid_file,
                  std::unique_ptr<VelocityModel>* out);

}  // namespace weaver
