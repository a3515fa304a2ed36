#include "serve/tiles.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "slice/canvas.h"
#include "slice/png.h"

namespace weaver::serve {
namespace {

constexpr int kTile = 256;

// How far the domain reaches along axis a from the origin corner: the first
// tick where a point on that edge is outside (a binary search by locate).
// A domain without its origin corner is taken as the whole root.
Status extent_along(Explorer& ex, int a, double* extent) {
  PointHit h;
  WEAVER_RETURN_IF_ERROR(ex.locate({0, 0, 0}, &h));
  if (!h.inside) return *extent = kRootEdge, Status::Ok();
  uint64_t lo = 0, hi = kRootEdge;  // inside at lo, outside at hi
  while (hi - lo > 1) {
    const uint64_t mid = (lo + hi) / 2;
    Coord c{0, 0, 0};
    (a == 0 ? c.x : a == 1 ? c.y : c.z) = uint32_t(mid);
    WEAVER_RETURN_IF_ERROR(ex.locate(c, &h));
    (h.inside ? lo : hi) = mid;
  }
  // The leaf at lo ends the domain on that edge.
  Coord c{0, 0, 0};
  (a == 0 ? c.x : a == 1 ? c.y : c.z) = uint32_t(lo);
  WEAVER_RETURN_IF_ERROR(ex.locate(c, &h));
  const uint32_t start = a == 0 ? h.leaf.x : a == 1 ? h.leaf.y : h.leaf.z;
  *extent = double(start) + octant_edge(h.leaf);
  return Status::Ok();
}

double value_of(const PointHit& h, const std::string& field, double tick_m) {
  if (field == "level") return h.leaf.level;
  if (field == "edge") return octant_edge(h.leaf) * tick_m;
  if (field == "vp") return h.vp;
  if (field == "vs") return h.vs;
  if (field == "rho") return h.rho;
  if (field == "qp") return h.qp;
  return h.qs;
}

// The points at the centres of an n x n grid over the square of side
// `span` ticks whose top-left corner is (u0, v0) on the page.
std::vector<Coord> grid(const Section& s, double u0, double v0, double span, int n) {
  std::vector<Coord> pts(size_t(n) * n);
  const double step = span / n;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double u = u0 + (i + 0.5) * step;
      const double v = s.down ? v0 + (j + 0.5) * step : v0 - (j + 0.5) * step;
      uint32_t c[3];
      c[s.axis] = s.at;
      c[s.u] = u >= 0 && u < kRootEdge ? uint32_t(u) : UINT32_MAX;
      c[s.v] = v >= 0 && v < kRootEdge ? uint32_t(v) : UINT32_MAX;
      pts[size_t(j) * n + i] = {c[0], c[1], c[2]};
    }
  }
  return pts;
}

}  // namespace

Status domain_extent(Explorer& ex, double extent[3]) {
  for (int a = 0; a < 3; ++a) WEAVER_RETURN_IF_ERROR(extent_along(ex, a, &extent[a]));
  return Status::Ok();
}

Status section_of(Explorer& ex, int axis, double at_m, Section* s) {
  double extent[3];
  WEAVER_RETURN_IF_ERROR(domain_extent(ex, extent));
  return section_of(ex, extent, axis, at_m, s);
}

Status section_of(Explorer& ex, const double extent[3], int axis, double at_m, Section* s) {
  if (axis < 0 || axis > 2) return Status::InvalidArgument("axis is x, y or z");
  *s = Section{};
  for (int a = 0; a < 3; ++a) s->extent[a] = extent[a];
  s->axis = axis;
  s->u = axis == 0 ? 1 : 0;
  s->v = axis == 2 ? 1 : 2;
  s->down = axis != 2;
  const Units& u = ex.units();
  const double t = std::floor((at_m - u.origin_m[axis]) / u.tick_m);
  if (!(t >= 0 && t < s->extent[axis])) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "the plane %c = %g m misses the domain (%g to %g m)",
                  "xyz"[axis], at_m, u.origin_m[axis],
                  u.origin_m[axis] + s->extent[axis] * u.tick_m);
    return Status::InvalidArgument(buf);
  }
  s->at = uint32_t(t);
  s->side = std::max(s->extent[s->u], s->extent[s->v]);
  return Status::Ok();
}

Status check_field(Explorer& ex, const std::string& field) {
  const bool material = field == "vp" || field == "vs" || field == "rho";
  const bool q = field == "qp" || field == "qs";
  if (!material && !q && field != "level" && field != "edge") {
    return Status::InvalidArgument("color is level, edge, vp, vs, rho, qp or qs, not '" + field +
                                   "'");
  }
  if ((material || q) && !ex.mesh().has_material()) {
    return Status::InvalidArgument("this mesh has no material (it was not built from a model)");
  }
  if (q && !ex.mesh().has_q()) return Status::InvalidArgument("this mesh has no qp and qs");
  return Status::Ok();
}

Status field_range(Explorer& ex, const Section& s, const std::string& field, FieldRange* r) {
  constexpr int kGrid = 256;  // as many points as a tile: as fast as one
  const std::vector<Coord> pts = grid(s, 0, s.down ? 0 : s.side, s.side, kGrid);
  std::vector<PointHit> hits(pts.size());
  WEAVER_RETURN_IF_ERROR(ex.locate_batch(pts.data(), pts.size(), hits.data()));
  *r = FieldRange{INFINITY, -INFINITY, 0};
  for (const PointHit& h : hits) {
    if (!h.inside) continue;
    const double v = value_of(h, field, ex.units().tick_m);
    r->min = std::min(r->min, v), r->max = std::max(r->max, v);
    ++r->samples;
  }
  if (r->samples == 0) r->min = r->max = 0;
  return Status::Ok();
}

Status render_tile(Explorer& ex, const Section& s, const std::string& field, double lo, double hi,
                   int zoom, int64_t x, int64_t y, std::string* png) {
  if (zoom < 0 || zoom > 30) return Status::InvalidArgument("zoom is 0 to 30");
  const double span = s.side / std::ldexp(1.0, zoom);
  const double u0 = x * span, v0 = s.down ? y * span : s.side - y * span;
  const std::vector<Coord> pts = grid(s, u0, v0, span, kTile);
  std::vector<PointHit> hits(pts.size());
  WEAVER_RETURN_IF_ERROR(ex.locate_batch(pts.data(), pts.size(), hits.data()));
  Image image(kTile, kTile, Rgb{255, 255, 255});
  const double pixel = span / kTile;  // ticks a pixel
  for (int j = 0; j < kTile; ++j) {
    for (int i = 0; i < kTile; ++i) {
      const PointHit& h = hits[size_t(j) * kTile + i];
      if (!h.inside) continue;
      const double t = hi > lo ? (value_of(h, field, ex.units().tick_m) - lo) / (hi - lo) : 0.5;
      Rgb c = colormap(std::clamp(t, 0.0, 1.0));
      // An outline where an element is at least 6 pixels wide and the pixel
      // before (left or above) lies in another element.
      if (octant_edge(h.leaf) >= 6 * pixel &&
          ((i > 0 && hits[size_t(j) * kTile + i - 1].id != h.id) ||
           (j > 0 && hits[size_t(j - 1) * kTile + i].id != h.id))) {
        c = kOutline;
      }
      image.set(i, j, c);
    }
  }
  *png = encode_png(image, {});
  return Status::Ok();
}

}  // namespace weaver::serve
