// Seismic velocity models: P and S wave speeds and density at a point.
// Coordinates are metres from the domain origin: x and y horizontal, z depth
// (positive down).
#pragma once

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
  // A one-line description with the parameters, for logs and metadata.
  virtual std::string describe() const = 0;
};

// "halfspace", "loh1", "basin", or "grid" (with grid_file).  InvalidArgument
// for an unknown name; grid file errors name the file.
Status make_model(const std::string& name, const std::string& grid_file,
                  std::unique_ptr<VelocityModel>* out);

}  // namespace weaver
