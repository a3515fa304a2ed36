#include "serve/tiles.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "slice/canvas.h"
#include "slice/png.h"

namespace weaver::serve {
namespace {

// What a pixel outside every element shows: transparent (the PNG's one
// transparent colour, which nothing else paints).
constexpr Rgb kClear{0, 0, 0};

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

// A material field's index in the aggregate records (-1 for level, edge).
int aggregate_index(const std::string& field) {
  for (size_t f = 0; f < kAggregateFields.size(); ++f) {
    if (field == kAggregateFields[f]) return int(f);
  }
  return -1;
}

// The summary s of field over an aggregate's leaves.
double value_of(const Aggregate& a, const std::string& field, Paint::Summary s, double tick_m) {
  using S = Paint::Summary;
  if (field == "level") return s == S::kMin ? a.level_min : a.level_max;
  // The least edge is that of the finest level.
  if (field == "edge") return octant_edge(s == S::kMin ? a.level_max : a.level_min) * tick_m;
  const int f = aggregate_index(field);
  return s == S::kMin ? a.min[f] : s == S::kMax ? a.max[f] : a.mean[f];
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

// The level whose octants are as wide as a pixel of `pixel` ticks or less.
int pixel_level(double pixel) {
  int level = 0;
  while (level < kMaxLevel && octant_edge(level) > pixel) ++level;
  return level;
}

// A pixel that shows the summary a of the elements in its octant.
void summarise(TilePixel* p, const Aggregate& a, const Paint& paint, double tick_m) {
  p->value = value_of(a, paint.field, paint.summary, tick_m);
  p->lo = value_of(a, paint.field, Paint::Summary::kMin, tick_m);
  p->hi = value_of(a, paint.field, Paint::Summary::kMax, tick_m);
}

// The pixels finer than the aggregate table's finest level whose element is
// smaller than they are: summarised from the leaves, as far as the budget
// goes; the rest from the table's finest octants, wider than the pixel.
Status summarise_finer(Explorer& ex, const Paint& paint, int level, const std::vector<Coord>& pts,
                       const std::vector<size_t>& at, std::vector<TilePixel>* out) {
  std::vector<AggregateHit> sums(pts.size());
  WEAVER_RETURN_IF_ERROR(
      ex.summarise_batch(pts.data(), pts.size(), level, kOnTheFlyLeaves, sums.data()));
  std::vector<Coord> rest;
  std::vector<size_t> where;
  for (size_t k = 0; k < pts.size(); ++k) {
    if (!sums[k].found) rest.push_back(pts[k]), where.push_back(k);
  }
  std::vector<AggregateHit> wide(rest.size());
  WEAVER_RETURN_IF_ERROR(
      ex.aggregate_batch(rest.data(), rest.size(), ex.aggregate_finest(), wide.data()));
  for (size_t k = 0; k < rest.size(); ++k) {
    sums[where[k]] = wide[k];
    (*out)[at[where[k]]].wide = true;
  }
  for (size_t k = 0; k < pts.size(); ++k) {
    if (sums[k].found) summarise(&(*out)[at[k]], sums[k].a, paint, ex.units().tick_m);
  }
  return Status::Ok();
}

// The pixels of an n x n grid over the square of side `span` ticks whose
// top-left corner is (u0, v0) on the page.
Status sample(Explorer& ex, const Section& s, const Paint& paint, double u0, double v0, double span,
              int n, std::vector<TilePixel>* out) {
  const std::vector<Coord> pts = grid(s, u0, v0, span, n);
  const double tick_m = ex.units().tick_m;
  out->assign(pts.size(), TilePixel{});
  const int level = pixel_level(span / n);
  const bool summaries = paint.summary != Paint::Summary::kCentre && level < kMaxLevel;
  const bool from_table = summaries && level <= ex.aggregate_finest();
  // Where the table holds the pixels' level, it goes first: a pixel whose
  // octant has a record holds many elements and shows their summary; it
  // needs no element of its own (no outline is drawn on it).
  std::vector<size_t> open;
  if (from_table) {
    std::vector<AggregateHit> sums(pts.size());
    WEAVER_RETURN_IF_ERROR(ex.aggregate_batch(pts.data(), pts.size(), level, sums.data()));
    for (size_t i = 0; i < pts.size(); ++i) {
      if (!sums[i].found) {
        open.push_back(i);
        continue;
      }
      const Octant o = octant_from_key(octant_key_ancestor(pixel_key(pts[i]), level));
      TilePixel& p = (*out)[i];
      p.inside = true, p.id = ~octant_key(o), p.leaf = o;  // ids no element has
      summarise(&p, sums[i].a, paint, tick_m);
    }
  } else {
    for (size_t i = 0; i < pts.size(); ++i) open.push_back(i);
  }
  // The element at the centre of each other pixel.
  std::vector<Coord> rest(open.size());
  for (size_t k = 0; k < open.size(); ++k) rest[k] = pts[open[k]];
  std::vector<PointHit> hits(rest.size());
  WEAVER_RETURN_IF_ERROR(ex.locate_batch(rest.data(), rest.size(), hits.data()));
  std::vector<Coord> finer;
  std::vector<size_t> at;
  for (size_t k = 0; k < rest.size(); ++k) {
    const PointHit& h = hits[k];
    if (!h.inside) continue;
    const double v = value_of(h, paint.field, tick_m);
    (*out)[open[k]] = {true, h.id, h.leaf, v, v, v};
    if (summaries && !from_table && h.leaf.level > level) {
      finer.push_back(rest[k]), at.push_back(open[k]);
    }
  }
  if (finer.empty()) return Status::Ok();
  return summarise_finer(ex, paint, level, finer, at, out);
}

// The dangling nodes on the plane: those on the faces that the elements at
// least 6 pixels wide have in it (their corners, edge midpoints and
// centres), found by one batch of node lookups; each a 5 x 5 square.
Status mark_danglings(Explorer& ex, const Section& s, const std::vector<TilePixel>& pixels,
                      double u0, double v0, double pixel, Image* image) {
  std::set<uint64_t> seen;
  std::vector<Coord> points;
  for (const TilePixel& p : pixels) {
    const uint32_t edge = octant_edge(p.leaf);
    const uint32_t corner[3] = {p.leaf.x, p.leaf.y, p.leaf.z};
    if (!p.inside || edge < 6 * pixel || corner[s.axis] != s.at || !seen.insert(p.id).second) {
      continue;
    }
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        uint32_t c[3] = {corner[0], corner[1], corner[2]};
        c[s.u] += uint32_t(a) * (edge / 2), c[s.v] += uint32_t(b) * (edge / 2);
        points.push_back({c[0], c[1], c[2]});
      }
    }
  }
  std::vector<NodeHit> hits(points.size());
  WEAVER_RETURN_IF_ERROR(ex.node_at_batch(points.data(), points.size(), hits.data()));
  for (size_t k = 0; k < points.size(); ++k) {
    if (!hits[k].found || hits[k].kind == NodeKind::kAnchored) continue;
    const uint32_t c[3] = {points[k].x, points[k].y, points[k].z};
    const int i = int(std::floor((c[s.u] - u0) / pixel));
    const int j = int(std::floor(s.down ? (c[s.v] - v0) / pixel : (v0 - c[s.v]) / pixel));
    const Rgb fill = hits[k].kind == NodeKind::kEdge ? Rgb{220, 30, 30} : Rgb{255, 255, 255};
    for (int dj = -2; dj <= 2; ++dj) {
      for (int di = -2; di <= 2; ++di) {
        if (i + di < 0 || i + di >= kTile || j + dj < 0 || j + dj >= kTile) continue;
        const bool rim = std::abs(di) == 2 || std::abs(dj) == 2;
        image->set(i + di, j + dj, rim ? kOutline : fill);
      }
    }
  }
  return Status::Ok();
}

// Where the pixel columns of a vertical section's tile cross the ground (a
// mesh under a surface): a line two pixels thick, the surface as construct
// read it (bilinear between its grid points), as `weaver slice` draws it.
void draw_ground(Explorer& ex, const Section& s, double u0, double v0, double pixel, Image* image) {
  const Units& u = ex.units();
  const double top = ex.mesh().top_elevation();
  for (int i = 0; i < kTile; ++i) {
    const double across = u0 + (i + 0.5) * pixel;
    if (!(across >= 0 && across < kRootEdge)) continue;
    uint32_t p[3];
    p[s.axis] = s.at, p[s.u] = uint32_t(across), p[s.v] = 0;
    const double ground = ex.ground_at({p[0], p[1], p[2]});
    if (std::isnan(ground)) return;                              // no surface to read
    const double z = (top - ground - u.origin_m[2]) / u.tick_m;  // ticks down
    const int j = int(std::floor((z - v0) / pixel));
    image->set(i, j - 1, kGroundLine), image->set(i, j, kGroundLine);
  }
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

Status paint_of(Explorer& ex, const std::string& field, const std::string& summary, Paint* out) {
  using S = Paint::Summary;
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
  out->field = field;
  if (summary.empty()) {
    out->summary = field == "rho" ? S::kMean : field == "level" ? S::kMax : S::kMin;
  } else if (summary == "min" || summary == "max" || summary == "mean") {
    out->summary = summary == "min" ? S::kMin : summary == "max" ? S::kMax : S::kMean;
    if (out->summary == S::kMean && !material && !q) {
      return Status::InvalidArgument("summary=mean is for vp, vs, rho, qp and qs, not " + field);
    }
  } else if (summary == "centre" || summary == "center") {
    out->summary = S::kCentre;
  } else {
    return Status::InvalidArgument("summary is min, max, mean or centre, not '" + summary + "'");
  }
  if (ex.aggregate_finest() < 0) out->summary = S::kCentre;
  return Status::Ok();
}

const char* summary_name(Paint::Summary s) {
  using S = Paint::Summary;
  return s == S::kMin ? "min" : s == S::kMax ? "max" : s == S::kMean ? "mean" : "centre";
}

std::string paint_caption(const Paint& p) {
  using S = Paint::Summary;
  if (p.summary == S::kCentre) return p.field + " of the element at each pixel's centre";
  const bool level = p.field == "level";
  const char* how = p.summary == S::kMean  ? "mean"
                    : p.summary == S::kMin ? (level ? "coarsest" : "least")
                                           : (level ? "finest" : "greatest");
  return std::string(how) + " " + p.field + " of the elements in each pixel" +
         (p.summary == S::kMean ? " (by volume)" : "");
}

Status tile_pixels(Explorer& ex, const Section& s, const Paint& paint, int zoom, int64_t x,
                   int64_t y, std::vector<TilePixel>* out) {
  if (zoom < 0 || zoom > 30) return Status::InvalidArgument("zoom is 0 to 30");
  const double span = s.side / std::ldexp(1.0, zoom);
  const double u0 = x * span, v0 = s.down ? y * span : s.side - y * span;
  return sample(ex, s, paint, u0, v0, span, kTile, out);
}

Status field_range(Explorer& ex, const Section& s, const Paint& paint, FieldRange* r) {
  std::vector<TilePixel> pixels;  // those of zoom 0: as fast as its tile
  WEAVER_RETURN_IF_ERROR(tile_pixels(ex, s, paint, 0, 0, 0, &pixels));
  *r = FieldRange{INFINITY, -INFINITY, 0};
  for (const TilePixel& p : pixels) {
    if (!p.inside) continue;
    r->min = std::min(r->min, p.lo), r->max = std::max(r->max, p.hi);
    ++r->samples;
  }
  if (r->samples == 0) r->min = r->max = 0;
  return Status::Ok();
}

Status render_tile(Explorer& ex, const Section& s, const Paint& paint, double lo, double hi,
                   int zoom, int64_t x, int64_t y, std::string* png, bool danglings) {
  std::vector<TilePixel> pixels;
  WEAVER_RETURN_IF_ERROR(tile_pixels(ex, s, paint, zoom, x, y, &pixels));
  Image image(kTile, kTile, kClear);
  const double span = s.side / std::ldexp(1.0, zoom);
  const double pixel = span / kTile;  // ticks a pixel
  for (int j = 0; j < kTile; ++j) {
    for (int i = 0; i < kTile; ++i) {
      const TilePixel& h = pixels[size_t(j) * kTile + i];
      if (!h.inside) continue;
      const double t = hi > lo ? (h.value - lo) / (hi - lo) : 0.5;
      Rgb c = colormap(std::clamp(t, 0.0, 1.0));
      // An outline where an element is at least 6 pixels wide and the pixel
      // before (left or above) lies in another element.
      if (octant_edge(h.leaf) >= 6 * pixel &&
          ((i > 0 && pixels[size_t(j) * kTile + i - 1].id != h.id) ||
           (j > 0 && pixels[size_t(j - 1) * kTile + i].id != h.id))) {
        c = kOutline;
      }
      image.set(i, j, c);
    }
  }
  const double u0 = x * span, v0 = s.down ? y * span : s.side - y * span;
  if (s.v == 2 && ex.mesh().has_ground()) draw_ground(ex, s, u0, v0, pixel, &image);
  if (danglings && ex.has_nodes()) {
    WEAVER_RETURN_IF_ERROR(mark_danglings(ex, s, pixels, u0, v0, pixel, &image));
  }
  *png = encode_png(image, {}, &kClear);
  return Status::Ok();
}

}  // namespace weaver::serve
