// Bounds on the synthetic basin's Vs over boxes (VelocityModel::vs_bounds
// and vs_bounds_of_eighths for the basin of basin_model.cc).
#pragma once

namespace weaver::basin {

// *vs_lo <= Vs <= *vs_hi at every point of the closed box [lo, hi], as the
// basin's at() rounds it.
void vs_bounds(const double lo[3], const double hi[3], float* vs_lo, float* vs_hi);
// The same for each of the eight halves c of a box with want[c]
// (VelocityModel::vs_bounds_of_eighths' edges), the same to the bit.
void vs_bounds_of_eighths(const double edges[3][3], const bool want[8], float vs_lo[8],
                          float vs_hi[8]);

}  // namespace weaver::basin
