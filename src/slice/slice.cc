#include "slice/slice.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include "db/leaf_window.h"
#include "export/output_file.h"
#include "mesh/octant_query.h"
#include "query/explorer.h"
#include "slice/canvas.h"
#include "slice/font.h"

namespace weaver {
namespace {

// The elements the plane cuts, each with its field value, in key order.
struct Cut {
  Octant o;
  double value;
};

class Slicer {
 public:
  Slicer(Explorer& ex, const SliceOptions& o, uint32_t at)
      : ex_(ex), o_(o), at_(at), window_(ex.mesh().octants(), true) {}

  // Limits the in-plane axes to lo[0]..hi[0] (u) and lo[1]..hi[1] (v), ticks.
  void limit(const uint32_t lo[2], const uint32_t hi[2]) {
    for (int i = 0; i < 2; ++i) lo_[i] = lo[i], hi_[i] = hi[i];
  }

  // Calls fn for each element the plane cuts.
  Status each(const std::function<void(const Cut&)>& fn) {
    TickBox box{{0, 0, 0}, {kRootEdge - 1, kRootEdge - 1, kRootEdge - 1}};
    uint32_t* lo[3] = {&box.lo.x, &box.lo.y, &box.lo.z};
    uint32_t* hi[3] = {&box.hi.x, &box.hi.y, &box.hi.z};
    *lo[o_.axis] = *hi[o_.axis] = at_;
    *lo[u()] = lo_[0], *hi[u()] = hi_[0];
    *lo[v()] = lo_[1], *hi[v()] = hi_[1];
    Status failed;
    uint64_t count = 0;
    MeshElement m;
    const Status st =
        range_query(ex_.mesh().octants(), box, &count, [&](const Octant& o, uint64_t) {
          if (!failed.ok()) return;
          double v = o.level;
          if (o_.color != "level") {
            LeafWindow::Floor f;
            failed = window_.floor(octant_key(o), &f);
            ex_.mesh().fill_material(f.payload, &m);
            v = o_.color == "vp" ? m.vp : o_.color == "vs" ? m.vs : m.rho;
          }
          fn({o, v});
        });
    return st.ok() ? failed : st;
  }

  // The in-plane axes: u across the picture, v up it.
  int u() const { return o_.axis == 0 ? 1 : 0; }
  int v() const { return o_.axis == 2 ? 1 : 2; }

 private:
  Explorer& ex_;
  const SliceOptions& o_;
  uint32_t at_;
  uint32_t lo_[2] = {0, 0}, hi_[2] = {kRootEdge - 1, kRootEdge - 1};
  LeafWindow window_;
};

uint32_t axis_of(const Octant& o, int a) { return a == 0 ? o.x : a == 1 ? o.y : o.z; }

std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

// Pixels of the picture: the plot's rectangle and the world it shows.
struct Layout {
  int font = 1, width = 0, height = 0;
  int left = 0, top = 0, plot_w = 0, plot_h = 0;
  double u0 = 0, v0 = 0, u1 = 0, v1 = 0;  // ticks
  double scale = 1;                       // pixels per tick
  bool down = false;                      // v grows downwards: z is depth, so sections show it so
  double x(double u) const { return left + (u - u0) * scale; }
  double y(double v) const { return top + (down ? v - v0 : v1 - v) * scale; }
};

// Round steps (1, 2 or 5 times a power of ten) about n to a span.
double nice_step(double span, int n) {
  const double raw = span / n, p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * p >= raw) return m * p;
  }
  return 10 * p;
}

void draw_axes(Canvas& c, const Layout& l, const Units& u, int ua, int va,
               const std::string& title) {
  const Rgb black{0, 0, 0};
  const int f = l.font;
  const double span = (l.u1 - l.u0) * u.tick_m;
  const bool km = span >= 2000;
  const double unit = km ? 1000 : 1;
  const char* axis_names = "xyz";
  auto ticks = [&](int a, double t0, double t1, bool horizontal) {
    const double w0 = (u.origin_m[a] + t0 * u.tick_m) / unit,
                 w1 = (u.origin_m[a] + t1 * u.tick_m) / unit;
    const double step = nice_step(w1 - w0, 6);
    for (double w = std::ceil(w0 / step) * step; w <= w1 + 1e-9 * step; w += step) {
      const double t = ((w * unit) - u.origin_m[a]) / u.tick_m;
      const std::string s = number_text(std::abs(w) < 1e-9 * step ? 0 : w);
      if (horizontal) {
        const double px = l.x(t);
        c.rect(px, l.top + l.plot_h, px + 1, l.top + l.plot_h + 4 * f, black, false);
        c.text(px, l.top + l.plot_h + 6 * f, s, f, black, Canvas::Align::kCenter);
      } else {
        const double py = l.y(t);
        c.rect(l.left - 4 * f, py, l.left, py + 1, black, false);
        c.text(l.left - 6 * f, py - 3 * f, s, f, black, Canvas::Align::kRight);
      }
    }
  };
  ticks(ua, l.u0, l.u1, true);
  ticks(va, l.v0, l.v1, false);
  const std::string unit_name = km ? " (km)" : " (m)";
  c.text(l.left + l.plot_w / 2.0, l.top + l.plot_h + 16 * f,
         std::string(1, axis_names[ua]) + unit_name, f, black, Canvas::Align::kCenter);
  c.text(2 * f, l.top - 10 * f,
         std::string(1, axis_names[va]) + unit_name + (l.down ? ", down" : ""), f, black,
         Canvas::Align::kLeft);
  c.text(l.left + l.plot_w / 2.0, 4 * f, title, f, black, Canvas::Align::kCenter);
  // The plot's frame.
  c.rect(l.left - 1, l.top - 1, l.left + l.plot_w + 1, l.top, black, false);
  c.rect(l.left - 1, l.top + l.plot_h, l.left + l.plot_w + 1, l.top + l.plot_h + 1, black, false);
  c.rect(l.left - 1, l.top, l.left, l.top + l.plot_h, black, false);
  c.rect(l.left + l.plot_w, l.top, l.left + l.plot_w + 1, l.top + l.plot_h, black, false);
}

void draw_colour_bar(Canvas& c, const Layout& l, double lo, double hi, bool levels) {
  const int f = l.font;
  const double x0 = l.left + l.plot_w + 14 * f, x1 = x0 + 12 * f;
  const double h = l.plot_h;
  const int steps = std::max(1, int(h));
  for (int i = 0; i < steps; ++i) {
    const double t =
        levels && hi > lo
            ? (std::floor(lo + (hi - lo + 1) * (1 - (i + 0.5) / steps)) - lo) / (hi - lo)
            : 1 - (i + 0.5) / steps;
    c.rect(x0, l.top + i * h / steps, x1, l.top + (i + 1) * h / steps, colormap(t), false);
  }
  const Rgb black{0, 0, 0};
  auto label = [&](double v) {
    const double t = hi > lo ? (v - lo) / (hi - lo) : 0.5;
    const double y =
        levels && hi > lo ? l.top + h * (1 - (v - lo + 0.5) / (hi - lo + 1)) : l.top + h * (1 - t);
    c.rect(x1, y, x1 + 3 * f, y + 1, black, false);
    c.text(x1 + 5 * f, y - 3 * f, number_text(v), f, black, Canvas::Align::kLeft);
  };
  if (levels) {
    for (double v = lo; v <= hi; ++v) label(v);
  } else if (hi > lo) {
    const double step = nice_step(hi - lo, 5);
    for (double v = std::ceil(lo / step) * step; v <= hi; v += step) label(v);
  } else {
    label(lo);
  }
}

Status plane_tick(Explorer& ex, const SliceOptions& o, uint32_t* at) {
  const Units& u = ex.units();
  const double at_m =
      o.at_is_elevation && o.axis == 2 ? ex.mesh().top_elevation() - o.at_m : o.at_m;
  const double t = o.at_is_ticks ? at_m : std::floor((at_m - u.origin_m[o.axis]) / u.tick_m);
  if (!(t >= 0 && t < kRootEdge)) {
    return Status::InvalidArgument("the plane " + std::string(1, "xyz"[o.axis]) + " = " +
                                   number_text(o.at_m) + (o.at_is_ticks ? " ticks" : " m") +
                                   " is outside the domain");
  }
  *at = uint32_t(t);
  return Status::Ok();
}

// Marks the dangling nodes on the plane: those on the lower faces of the
// cut elements that lie in it (corners, edge midpoints, centres).
Status mark_danglings(Explorer& ex, Slicer& s, Canvas& c, const Layout& l, int axis, uint32_t at,
                      uint64_t* marked) {
  std::vector<Coord> points;
  std::vector<NodeHit> hits;
  auto flush = [&]() -> Status {
    hits.resize(points.size());
    WEAVER_RETURN_IF_ERROR(ex.node_at_batch(points.data(), points.size(), hits.data()));
    for (size_t i = 0; i < points.size(); ++i) {
      if (!hits[i].found || hits[i].kind == NodeKind::kAnchored) continue;
      const uint32_t p[3] = {points[i].x, points[i].y, points[i].z};
      const double x = l.x(p[s.u()]), y = l.y(p[s.v()]);
      if (x < l.left || x > l.left + l.plot_w || y < l.top || y > l.top + l.plot_h) continue;
      const double r = l.font;
      c.rect(x - r, y - r, x + r + 1, y + r + 1,
             hits[i].kind == NodeKind::kEdge ? Rgb{220, 30, 30} : Rgb{255, 255, 255}, true);
      ++*marked;
    }
    points.clear();
    return Status::Ok();
  };
  Status st;
  WEAVER_RETURN_IF_ERROR(s.each([&](const Cut& cut) {
    if (!st.ok() || axis_of(cut.o, axis) != at || cut.o.level == kMaxLevel) return;
    const uint32_t h = octant_edge(cut.o) / 2;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        uint32_t p[3] = {cut.o.x, cut.o.y, cut.o.z};
        p[s.u()] += i * h, p[s.v()] += j * h;
        points.push_back({p[0], p[1], p[2]});
      }
    if (points.size() >= 1 << 20) st = flush();
  }));
  WEAVER_RETURN_IF_ERROR(st);
  return flush();
}

}  // namespace

// The ground where it crosses a vertical section (a mesh built under a
// surface): a dark line over the elements, a pixel column at a time, the
// surface as construct read it (bilinear between its grid points).
void draw_ground(Explorer& ex, Canvas& c, const Layout& l, int ua, int axis, uint32_t at) {
  const Units& u = ex.units();
  const double top = ex.mesh().top_elevation();
  for (int px = l.left; px < l.left + l.plot_w; ++px) {
    const double tick = l.u0 + (px + 0.5 - l.left) / l.scale;
    uint32_t p[3] = {0, 0, 0};
    p[axis] = at;
    p[ua] = uint32_t(std::clamp(tick, 0.0, double(kRootEdge - 1)));
    const double ground = ex.ground_at({p[0], p[1], p[2]});
    if (std::isnan(ground)) return;
    const double y = l.y((top - ground - u.origin_m[2]) / u.tick_m);
    if (y < l.top || y > l.top + l.plot_h) continue;
    c.rect(px, std::max(double(l.top), y - 1), px + 1, std::min(double(l.top + l.plot_h), y + 1),
           kGroundLine, false);
  }
}

Status render_slice(const std::string& db, const SliceOptions& o, const std::string& out,
                    SliceResult* r) {
  *r = SliceResult{};
  const bool svg = out.size() >= 4 && out.compare(out.size() - 4, 4, ".svg") == 0;
  const bool png = out.size() >= 4 && out.compare(out.size() - 4, 4, ".png") == 0;
  if (!svg && !png) return Status::InvalidArgument("--out must end in .png or .svg");
  if (o.width < 200 || o.width > 20000)
    return Status::InvalidArgument("--width must be 200 to 20000");
  if (o.color != "level" && o.color != "vp" && o.color != "vs" && o.color != "rho") {
    return Status::InvalidArgument("--color is level, vp, vs or rho, not '" + o.color + "'");
  }
  std::unique_ptr<Explorer> ex;
  WEAVER_RETURN_IF_ERROR(Explorer::open(db, o.memory, &ex));
  if (o.color != "level" && !ex->mesh().has_material()) {
    return Status::InvalidArgument("this mesh has no material: --color level");
  }
  if (o.danglings) WEAVER_RETURN_IF_ERROR(ex->require_nodes());
  WEAVER_RETURN_IF_ERROR(plane_tick(*ex, o, &r->at_ticks));
  Slicer s(*ex, o, r->at_ticks);
  uint32_t lo[2] = {0, 0}, hi[2] = {kRootEdge - 1, kRootEdge - 1};
  if (o.has_region) {
    const int axes[2] = {s.u(), s.v()};
    for (int i = 0; i < 2; ++i) {
      auto tick = [&](double w) {
        const double t =
            o.at_is_ticks ? w : (w - ex->units().origin_m[axes[i]]) / ex->units().tick_m;
        return uint32_t(std::clamp(std::floor(t), 0.0, double(kRootEdge - 1)));
      };
      lo[i] = tick(o.region[i]), hi[i] = tick(o.region[i + 2]);
      if (hi[i] <= lo[i])
        return Status::InvalidArgument("--region is empty on its " +
                                       std::string(i ? "second" : "first") + " axis");
    }
    s.limit(lo, hi);
  }
  // Pass 1: the extent and the field's range.
  Layout l;
  l.u0 = l.v0 = 1e18, l.u1 = l.v1 = -1;
  r->min = 1e300, r->max = -1e300;
  WEAVER_RETURN_IF_ERROR(s.each([&](const Cut& c) {
    const double e = octant_edge(c.o), u = axis_of(c.o, s.u()), v = axis_of(c.o, s.v());
    l.u0 = std::min(l.u0, u), l.u1 = std::max(l.u1, u + e);
    l.v0 = std::min(l.v0, v), l.v1 = std::max(l.v1, v + e);
    r->min = std::min(r->min, c.value), r->max = std::max(r->max, c.value);
    ++r->elements;
  }));
  // A region shows just itself, whatever the elements at its border reach.
  l.u0 = std::max(l.u0, double(lo[0])), l.u1 = std::min(l.u1, double(hi[0]) + 1);
  l.v0 = std::max(l.v0, double(lo[1])), l.v1 = std::min(l.v1, double(hi[1]) + 1);
  if (r->elements == 0) {
    return Status::InvalidArgument("the plane " + std::string(1, "xyz"[o.axis]) + " = " +
                                   number_text(o.at_m) + (o.at_is_ticks ? " ticks" : " m") +
                                   " cuts no element: it is outside the domain");
  }
  l.down = s.v() == 2;
  l.font = o.width >= 1200 ? 2 : 1;
  l.left = 60 * l.font, l.top = 28 * l.font;
  l.plot_w = o.width - l.left - 80 * l.font;
  l.scale = l.plot_w / (l.u1 - l.u0);
  l.plot_h = std::clamp(int(std::lround((l.v1 - l.v0) * l.scale)), 1, 20000);
  l.width = o.width, l.height = l.top + l.plot_h + 30 * l.font;
  OutputFile file(out);  // removed again unless finished
  WEAVER_RETURN_IF_ERROR(file.open());
  std::unique_ptr<Canvas> c =
      svg ? svg_canvas(l.width, l.height, &file) : png_canvas(l.width, l.height, &file);
  // Pass 2: the elements.
  const double span = r->max > r->min ? r->max - r->min : 1;
  WEAVER_RETURN_IF_ERROR(s.each([&](const Cut& cut) {
    const double e = octant_edge(cut.o), u = axis_of(cut.o, s.u()), v = axis_of(cut.o, s.v());
    const double ya = l.y(v), yb = l.y(v + e);
    // Clipped to the plot (elements at a region's border reach past it).
    const double x0 = std::max(l.x(u), double(l.left));
    const double x1 = std::min(l.x(u + e), double(l.left + l.plot_w));
    const double y0 = std::max(std::min(ya, yb), double(l.top));
    const double y1 = std::min(std::max(ya, yb), double(l.top + l.plot_h));
    if (x1 > x0 && y1 > y0) c->rect(x0, y0, x1, y1, colormap((cut.value - r->min) / span), true);
  }));
  if (s.v() == 2 && ex->mesh().has_ground()) draw_ground(*ex, *c, l, s.u(), o.axis, r->at_ticks);
  if (o.danglings) {
    WEAVER_RETURN_IF_ERROR(mark_danglings(*ex, s, *c, l, o.axis, r->at_ticks, &r->danglings));
  }
  static const char* const kUnit[] = {"", " (m/s)", " (m/s)", " (kg/m^3)"};
  const int field = o.color == "level" ? 0 : o.color == "vp" ? 1 : o.color == "vs" ? 2 : 3;
  const Units& u = ex->units();
  const double at_m = u.origin_m[o.axis] + r->at_ticks * u.tick_m;
  const std::string title =
      o.color + kUnit[field] + "   " + std::string(1, "xyz"[o.axis]) + " = " +
      (std::abs(at_m) >= 2000 ? number_text(at_m / 1000) + " km" : number_text(at_m) + " m");
  draw_axes(*c, l, u, s.u(), s.v(), title);
  draw_colour_bar(*c, l, r->min, r->max, field == 0);
  r->width = l.width, r->height = l.height;
  char plot[160], world[160], range[80];
  std::snprintf(plot, sizeof plot, "%d %d %d %d", l.left, l.top, l.left + l.plot_w,
                l.top + l.plot_h);
  std::snprintf(world, sizeof world, "%.0f %.0f %.0f %.0f", l.u0, l.v0, l.u1, l.v1);
  std::snprintf(range, sizeof range, "%.9g %.9g", r->min, r->max);
  WEAVER_RETURN_IF_ERROR(
      c->finish({{"weaver.field", o.color},
                 {"weaver.axes", std::string(1, "xyz"[s.u()]) + " " + "xyz"[s.v()]},
                 {"weaver.plane", std::to_string(r->at_ticks)},
                 {"weaver.plot", plot},
                 {"weaver.world", world},
                 {"weaver.range", range}}));
  return file.finish();
}

}  // namespace weaver
