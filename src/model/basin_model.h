// The synthetic basin (basin_model.cc): the built-in model that stands in for
// the SCEC model of the Los Angeles basin in the paper's runs.
#pragma once

#include <memory>

#include "model/velocity_model.h"

namespace weaver {

std::unique_ptr<VelocityModel> make_basin_model();

}  // namespace weaver
