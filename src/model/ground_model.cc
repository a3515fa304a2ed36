#include "model/ground_model.h"

#include <algorithm>

namespace weaver {

Status parse_model_z(const std::string& text, ModelZ* out) {
  if (text == "depth") {
    *out = ModelZ::kDepth;
  } else if (text == "elevation") {
    *out = ModelZ::kElevation;
  } else {
    return Status::InvalidArgument("--model-z '" + text + "': depth or elevation");
  }
  return Status::Ok();
}

const char* model_z_name(ModelZ z) { return z == ModelZ::kDepth ? "depth" : "elevation"; }

double Ground::model_z_of(double x, double y, double z) const {
  const double ground = ground_at(x, y);
  const double e = std::min(top_elevation - z, ground);
  return model_z == ModelZ::kElevation ? -e : ground - e;
}

GroundSide side_of_ground(const Ground& g, const double lo[3], const double hi[3]) {
  double g_lo = g.top_elevation, g_hi = g.top_elevation;
  if (g.surface) g.surface->range(lo[0], hi[0], lo[1], hi[1], &g_lo, &g_hi);
  if (hi[2] <= g.top_elevation - g_hi) return GroundSide::kAir;
  if (lo[2] >= g.top_elevation - g_lo) return GroundSide::kSolid;
  return GroundSide::kCut;
}

Material GroundedModel::at(double x, double y, double z) const {
  return inner_.at(x, y, g_.model_z_of(x, y, z));
}

// The model's z rises with the domain's z; with the ground it falls
// (elevation: the clamp to the ground) or rises (depth below it).
void GroundedModel::model_box(const double lo[3], const double hi[3], double mlo[3],
                              double mhi[3]) const {
  double g_lo = g_.top_elevation, g_hi = g_.top_elevation;
  if (g_.surface) g_.surface->range(lo[0], hi[0], lo[1], hi[1], &g_lo, &g_hi);
  const double top = g_.top_elevation;
  mlo[0] = lo[0], mlo[1] = lo[1], mhi[0] = hi[0], mhi[1] = hi[1];
  if (g_.model_z == ModelZ::kElevation) {
    mlo[2] = -std::min(top - lo[2], g_hi);
    mhi[2] = -std::min(top - hi[2], g_lo);
  } else {
    mlo[2] = std::max(g_lo - top + lo[2], 0.0);
    mhi[2] = std::max(g_hi - top + hi[2], 0.0);
  }
}

bool GroundedModel::vs_bounds(const double lo[3], const double hi[3], float* vs_lo,
                              float* vs_hi) const {
  double mlo[3], mhi[3];
  model_box(lo, hi, mlo, mhi);
  return inner_.vs_bounds(mlo, mhi, vs_lo, vs_hi);
}

void GroundedModel::focus(const double lo[3], const double hi[3]) const {
  double mlo[3], mhi[3];
  model_box(lo, hi, mlo, mhi);
  inner_.focus(mlo, mhi);
}

std::string GroundedModel::outside(const std::array<double, 3>& domain_m) const {
  const double lo[3] = {0, 0, 0}, hi[3] = {domain_m[0], domain_m[1], domain_m[2]};
  double mlo[3], mhi[3];
  model_box(lo, hi, mlo, mhi);
  return inner_.outside({domain_m[0], domain_m[1], mhi[2]});
}

}  // namespace weaver
