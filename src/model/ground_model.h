// A velocity model under a ground surface (model/surface.h), in the mesh's
// vertical frame: z is depth below the domain's top, whose elevation is
// top_elevation.  A point in the air takes the model's value at the ground
// under it (the highest solid point of its column), so a cut element whose
// centre is in the air never sees a model's no-data value.  The model is
// asked at its own vertical reference:
//   kElevation   z down from sea level (an rfile's z): -elevation
//   kDepth       depth below the local ground (UCVM's "depth" mode): the
//                built-in models, etree, grid, layers and xyz
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "model/surface.h"
#include "model/velocity_model.h"

namespace weaver {

enum class ModelZ { kDepth, kElevation };

// "depth" or "elevation"; InvalidArgument otherwise.
Status parse_model_z(const std::string& text, ModelZ* out);
const char* model_z_name(ModelZ z);

struct Ground {
  const Surface* surface = nullptr;  // null: flat, at top_elevation
  double top_elevation = 0;          // of z = 0, metres
  ModelZ model_z = ModelZ::kDepth;

  double ground_at(double x, double y) const {
    return surface ? surface->elevation(x, y) : top_elevation;
  }
  // The model's vertical coordinate of domain point (x, y, z), moved down
  // to the ground where it lies in the air.
  double model_z_of(double x, double y, double z) const;
};

// Which side of the ground the box [lo, hi] (metres; z down from the top)
// lies on: air when its bottom is at or above the highest ground over its
// footprint (exactly: Surface::range), solid when its top is at or below
// the lowest, else cut.
enum class GroundSide { kAir, kCut, kSolid };
GroundSide side_of_ground(const Ground& g, const double lo[3], const double hi[3]);

// The share of the box [lo, hi] below the ground: in (0, 1] for a box that
// is not air, 0 for air.  A cut box's is the mean, over 8 x 8 points at the
// centres of equal parts of its footprint, of the share of its height below
// the ground there (construct/carve.h says its error); a cut box the points
// all miss keeps at most 1/64, never 0.
double solid_fraction(const Ground& g, const double lo[3], const double hi[3]);

// The ground a mesh was built under, read again as its octant table's
// metadata names it (surface=, top_elevation_m=, surface_crs=, geo=).
// NotFound for a flat mesh; the surface's own error when it cannot be read.
Status ground_of_metadata(const std::string& metadata, uint64_t max_bytes,
                          std::unique_ptr<Surface>* surface, Ground* ground);

class GroundedModel final : public VelocityModel {
 public:
  GroundedModel(std::unique_ptr<VelocityModel> inner, Ground g)
      : own_(std::move(inner)), inner_(*own_), g_(g) {}

  Material at(double x, double y, double z) const override;
  // The ground once a column of the lattice, not once a point.
  void vs_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                     float* out) const override;
  void materials_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                            Material* out) const override;
  bool vs_bounds(const double lo[3], const double hi[3], float* vs_lo, float* vs_hi) const override;
  bool focus(const double lo[3], const double hi[3]) const override;
  bool loads_focus() const override { return inner_.loads_focus(); }
  bool has_q() const override { return inner_.has_q(); }
  std::string outside(const std::array<double, 3>& domain_m) const override;
  std::string geo() const override { return inner_.geo(); }
  std::string projection() const override { return inner_.projection(); }
  std::string describe() const override { return inner_.describe(); }

 private:
  // The model's box for the domain box [lo, hi].
  void model_box(const double lo[3], const double hi[3], double mlo[3], double mhi[3]) const;

  std::unique_ptr<VelocityModel> own_;
  const VelocityModel& inner_;
  Ground g_;
};

}  // namespace weaver
