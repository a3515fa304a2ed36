#include "model/ground_model.h"

#include <algorithm>
#include <cstdlib>
#include <vector>

#include "model/geo_frame.h"
#include "util/metadata_text.h"

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

// Settled by the cheapest test that can: the ground's whole range, the
// ground at the box's centre (inside the box's height: cut), the pyramid's
// loose bounds, and only then the exact range over the footprint.
GroundSide side_of_ground(const Ground& g, const double lo[3], const double hi[3]) {
  const double top = g.top_elevation;
  const Surface* s = g.surface;
  const auto side = [&](double g_lo, double g_hi) {
    if (hi[2] <= top - g_hi) return GroundSide::kAir;
    if (lo[2] >= top - g_lo) return GroundSide::kSolid;
    return GroundSide::kCut;
  };
  if (s == nullptr) return side(top, top);
  const GroundSide global = side(s->lowest(), s->highest());
  if (global != GroundSide::kCut) return global;
  const double centre = top - s->elevation((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2);
  if (lo[2] < centre && centre < hi[2]) return GroundSide::kCut;
  double g_lo, g_hi;
  s->loose_range(lo[0], hi[0], lo[1], hi[1], &g_lo, &g_hi);
  const GroundSide loose = side(g_lo, g_hi);
  if (loose != GroundSide::kCut) return loose;
  s->range(lo[0], hi[0], lo[1], hi[1], &g_lo, &g_hi);
  return side(g_lo, g_hi);
}

namespace {

constexpr int kFractionPoints = 8;

}  // namespace

double solid_fraction(const Ground& g, const double lo[3], const double hi[3]) {
  const GroundSide side = side_of_ground(g, lo, hi);
  if (side == GroundSide::kAir) return 0;
  if (side == GroundSide::kSolid) return 1;
  const double top = g.top_elevation, height = hi[2] - lo[2];
  const double sx = (hi[0] - lo[0]) / kFractionPoints, sy = (hi[1] - lo[1]) / kFractionPoints;
  double sum = 0;
  for (int j = 0; j < kFractionPoints; ++j) {
    for (int i = 0; i < kFractionPoints; ++i) {
      const double ground_z = top - g.ground_at(lo[0] + (i + 0.5) * sx, lo[1] + (j + 0.5) * sy);
      sum += std::clamp((hi[2] - std::max(lo[2], ground_z)) / height, 0.0, 1.0);
    }
  }
  const double f = sum / (kFractionPoints * kFractionPoints);
  if (f > 0) return f;
  // The ground reaches into the leaf between the points: the most it can
  // hold there, shared by one point's part.
  double g_lo, g_hi;
  g.surface->range(lo[0], hi[0], lo[1], hi[1], &g_lo, &g_hi);
  return std::min(1.0, (hi[2] - (top - g_hi)) / height) / (kFractionPoints * kFractionPoints);
}

Status ground_of_metadata(const std::string& metadata, uint64_t max_bytes,
                          std::unique_ptr<Surface>* surface, Ground* ground) {
  const std::string source = metadata_item(metadata, "surface");
  const std::string top = metadata_item(metadata, "top_elevation_m");
  if (source.empty() || source == "flat" || top.empty())
    return Status::NotFound("the mesh has no ground surface");
  SurfaceSource s;
  WEAVER_RETURN_IF_ERROR(parse_surface_source(source, &s));
  if (metadata_item(metadata, "surface_crs") == "lonlat") s.crs = SurfaceCrs::kLonLat;
  GeoFrame geo;
  const std::string geo_text = metadata_item(metadata, "geo");
  const bool has_geo = !geo_text.empty() && GeoFrame::parse(geo_text, &geo).ok();
  WEAVER_RETURN_IF_ERROR(load_surface(s, has_geo ? &geo : nullptr, max_bytes, surface));
  *ground = Ground{};
  ground->surface = surface->get();
  ground->top_elevation = std::strtod(top.c_str(), nullptr);
  ModelZ z;
  if (parse_model_z(metadata_item(metadata, "model_z"), &z).ok()) ground->model_z = z;
  return Status::Ok();
}

Material GroundedModel::at(double x, double y, double z) const {
  return inner_.at(x, y, g_.model_z_of(x, y, z));
}

namespace {

// The model's z at every lattice point, column by column (as
// VelocityModel::vs_on_columns takes them), the ground once a column.
void model_columns(const Ground& g, const double* xs, const double* ys, const double* zs, int n,
                   double* mz) {
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double ground = g.ground_at(xs[i], ys[j]);
      double* column = mz + (j * n + i) * n;
      for (int k = 0; k < n; ++k) {
        const double e = std::min(g.top_elevation - zs[k], ground);
        column[k] = g.model_z == ModelZ::kElevation ? -e : ground - e;
      }
    }
  }
}

// A lattice's model z's: on the stack for construct's (n up to 8: a block's
// centres).
class ColumnDepths {
 public:
  ColumnDepths(const Ground& g, const double* xs, const double* ys, const double* zs, int n) {
    const size_t points = size_t(n) * n * n;
    if (points > kOnStack) heap_.resize(points);
    data_ = points > kOnStack ? heap_.data() : stack_;
    model_columns(g, xs, ys, zs, n, data_);
  }
  const double* data() const { return data_; }

 private:
  static constexpr size_t kOnStack = 512;
  double stack_[kOnStack];
  std::vector<double> heap_;
  double* data_;
};

}  // namespace

void GroundedModel::vs_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                                  float* out) const {
  const ColumnDepths mz(g_, xs, ys, zs, n);
  inner_.vs_on_columns(xs, ys, mz.data(), n, out);
}

void GroundedModel::materials_on_lattice(const double* xs, const double* ys, const double* zs,
                                         int n, Material* out) const {
  const ColumnDepths mz(g_, xs, ys, zs, n);
  inner_.materials_on_columns(xs, ys, mz.data(), n, out);
}

// The model's z rises with the domain's z; with the ground it falls
// (elevation: the clamp to the ground) or rises (depth below it).
void GroundedModel::model_box(const double lo[3], const double hi[3], double mlo[3],
                              double mhi[3]) const {
  double g_lo = g_.top_elevation, g_hi = g_.top_elevation;
  // Loose bounds will do: a wider box only costs samples.
  if (g_.surface) g_.surface->loose_range(lo[0], hi[0], lo[1], hi[1], &g_lo, &g_hi);
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

bool GroundedModel::focus(const double lo[3], const double hi[3]) const {
  double mlo[3], mhi[3];
  model_box(lo, hi, mlo, mhi);
  return inner_.focus(mlo, mhi);
}

std::string GroundedModel::outside(const std::array<double, 3>& domain_m) const {
  const double lo[3] = {0, 0, 0}, hi[3] = {domain_m[0], domain_m[1], domain_m[2]};
  double mlo[3], mhi[3];
  model_box(lo, hi, mlo, mhi);
  return inner_.outside({domain_m[0], domain_m[1], mhi[2]});
}

}  // namespace weaver
