#include "model/surface.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <sstream>

#include "model/geo_frame.h"
#include "model/rfile.h"

namespace weaver {

std::unique_ptr<Surface> Surface::from_grid(int nx, int ny, double x0, double y0, double dx,
                                            double dy, std::vector<float> z) {
  std::unique_ptr<Surface> s(new Surface());
  s->nx_ = nx, s->ny_ = ny, s->x0_ = x0, s->y0_ = y0, s->dx_ = dx, s->dy_ = dy;
  s->z_ = std::move(z);
  s->build_pyramid();
  return s;
}

void Surface::build_pyramid() {
  min_ = HUGE_VAL, max_ = -HUGE_VAL;
  for (float v : z_) min_ = std::min<double>(min_, v), max_ = std::max<double>(max_, v);
  Level base;
  base.w = nx_ - 1, base.h = ny_ - 1;
  base.lo.resize(size_t(base.w) * base.h), base.hi.resize(base.lo.size());
  for (int j = 0; j < base.h; ++j) {
    for (int i = 0; i < base.w; ++i) {
      const float c[4] = {at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)};
      base.lo[size_t(j) * base.w + i] = *std::min_element(c, c + 4);
      base.hi[size_t(j) * base.w + i] = *std::max_element(c, c + 4);
    }
  }
  levels_.push_back(std::move(base));
  while (levels_.back().w > 1 || levels_.back().h > 1) {
    const Level& f = levels_.back();
    Level c;
    c.w = (f.w + 1) / 2, c.h = (f.h + 1) / 2;
    c.lo.assign(size_t(c.w) * c.h, HUGE_VALF), c.hi.assign(c.lo.size(), -HUGE_VALF);
    for (int j = 0; j < f.h; ++j) {
      for (int i = 0; i < f.w; ++i) {
        const size_t to = size_t(j / 2) * c.w + i / 2, from = size_t(j) * f.w + i;
        c.lo[to] = std::min(c.lo[to], f.lo[from]);
        c.hi[to] = std::max(c.hi[to], f.hi[from]);
      }
    }
    levels_.push_back(std::move(c));
  }
}

double Surface::elevation(double x, double y) const {
  const double u = std::clamp((x - x0_) / dx_, 0.0, double(nx_ - 1));
  const double v = std::clamp((y - y0_) / dy_, 0.0, double(ny_ - 1));
  const int i = std::min(int(u), nx_ - 2), j = std::min(int(v), ny_ - 2);
  const double wx = u - i, wy = v - j;
  return (1 - wy) * ((1 - wx) * at(i, j) + wx * at(i + 1, j)) +
         wy * ((1 - wx) * at(i, j + 1) + wx * at(i + 1, j + 1));
}

// A bilinear function on a rectangle is extreme at its corners (inside,
// its one critical point is a saddle; along an edge it is linear).
void Surface::cell_range(int i, int j, double u0, double u1, double v0, double v1, double* lo,
                         double* hi) const {
  const double a = std::max(u0, double(i)) - i, b = std::min(u1, double(i + 1)) - i;
  const double c = std::max(v0, double(j)) - j, d = std::min(v1, double(j + 1)) - j;
  const double z00 = at(i, j), z10 = at(i + 1, j), z01 = at(i, j + 1), z11 = at(i + 1, j + 1);
  for (double wx : {a, b}) {
    for (double wy : {c, d}) {
      const double z = (1 - wy) * ((1 - wx) * z00 + wx * z10) + wy * ((1 - wx) * z01 + wx * z11);
      *lo = std::min(*lo, z), *hi = std::max(*hi, z);
    }
  }
}

// The cells of block (bi, bj) of `level` that meet cells [ci0, ci1] x
// [cj0, cj1]: whole blocks inside the rectangle (u0..u1, v0..v1, in cells)
// by the pyramid, the rest cell by cell.
void Surface::block_range(int level, int bi, int bj, int ci0, int ci1, int cj0, int cj1, double u0,
                          double u1, double v0, double v1, double* lo, double* hi) const {
  const int first_i = bi << level, first_j = bj << level;
  const int last_i = std::min(((bi + 1) << level) - 1, nx_ - 2);
  const int last_j = std::min(((bj + 1) << level) - 1, ny_ - 2);
  if (last_i < ci0 || first_i > ci1 || last_j < cj0 || first_j > cj1) return;
  const bool whole = u0 <= first_i && last_i + 1 <= u1 && v0 <= first_j && last_j + 1 <= v1;
  if (whole) {
    const Level& l = levels_[level];
    *lo = std::min<double>(*lo, l.lo[size_t(bj) * l.w + bi]);
    *hi = std::max<double>(*hi, l.hi[size_t(bj) * l.w + bi]);
    return;
  }
  if (level == 0) {
    cell_range(bi, bj, u0, u1, v0, v1, lo, hi);
    return;
  }
  for (int dj = 0; dj < 2; ++dj) {
    for (int di = 0; di < 2; ++di) {
      block_range(level - 1, 2 * bi + di, 2 * bj + dj, ci0, ci1, cj0, cj1, u0, u1, v0, v1, lo, hi);
    }
  }
}

Surface::Span Surface::span_of(double x0, double x1, double y0, double y1) const {
  Span s;
  s.u0 = std::clamp((x0 - x0_) / dx_, 0.0, double(nx_ - 1));
  s.u1 = std::clamp((x1 - x0_) / dx_, 0.0, double(nx_ - 1));
  s.v0 = std::clamp((y0 - y0_) / dy_, 0.0, double(ny_ - 1));
  s.v1 = std::clamp((y1 - y0_) / dy_, 0.0, double(ny_ - 1));
  s.ci0 = std::min(int(s.u0), nx_ - 2), s.cj0 = std::min(int(s.v0), ny_ - 2);
  s.ci1 = std::clamp(int(std::ceil(s.u1)) - 1, s.ci0, nx_ - 2);
  s.cj1 = std::clamp(int(std::ceil(s.v1)) - 1, s.cj0, ny_ - 2);
  return s;
}

void Surface::range(double x0, double x1, double y0, double y1, double* lo, double* hi) const {
  const Span s = span_of(x0, x1, y0, y1);
  *lo = HUGE_VAL, *hi = -HUGE_VAL;
  block_range(int(levels_.size()) - 1, 0, 0, s.ci0, s.ci1, s.cj0, s.cj1, s.u0, s.u1, s.v0, s.v1, lo,
              hi);
}

void Surface::loose_range(double x0, double x1, double y0, double y1, double* lo,
                          double* hi) const {
  const Span s = span_of(x0, x1, y0, y1);
  const int ci0 = s.ci0, ci1 = s.ci1, cj0 = s.cj0, cj1 = s.cj1;
  // The level whose blocks are at least as wide as the span of cells: it
  // meets at most 2 of them along each axis.
  int level = 0;
  while (level + 1 < int(levels_.size()) &&
         ((ci1 - ci0 + 1) > (1 << level) || (cj1 - cj0 + 1) > (1 << level)))
    ++level;
  const Level& l = levels_[level];
  *lo = HUGE_VAL, *hi = -HUGE_VAL;
  for (int bj = cj0 >> level; bj <= cj1 >> level; ++bj) {
    for (int bi = ci0 >> level; bi <= ci1 >> level; ++bi) {
      *lo = std::min<double>(*lo, l.lo[size_t(bj) * l.w + bi]);
      *hi = std::max<double>(*hi, l.hi[size_t(bj) * l.w + bi]);
    }
  }
}

std::string Surface::outside(double lx, double ly) const {
  const double tol_x = 1e-6 * std::max(1.0, lx), tol_y = 1e-6 * std::max(1.0, ly);
  std::string sides;
  const auto add = [&](const char* s) { sides += sides.empty() ? s : std::string(", ") + s; };
  if (x0_ > tol_x) add("x-");
  if (x_hi() < lx - tol_x) add("x+");
  if (y0_ > tol_y) add("y-");
  if (y_hi() < ly - tol_y) add("y+");
  if (sides.empty()) return "";
  char buf[160];
  std::snprintf(buf, sizeof buf, " (it spans x %g to %g m, y %g to %g m)", x0_, x_hi(), y0_,
                y_hi());
  return "the surface does not cover the domain on " + sides + buf;
}

namespace {

// NODATA cells (NaN) take the nearest valid cell's value, breadth first.
uint64_t fill_nodata(int nx, int ny, std::vector<float>* z) {
  std::deque<size_t> queue;
  uint64_t missing = 0;
  for (size_t c = 0; c < z->size(); ++c) {
    if (std::isnan((*z)[c])) {
      ++missing;
    } else {
      queue.push_back(c);
    }
  }
  if (missing == 0 || queue.empty()) return missing;
  while (!queue.empty()) {
    const size_t c = queue.front();
    queue.pop_front();
    const int i = int(c % nx), j = int(c / nx);
    const int ni[4] = {i - 1, i + 1, i, i}, nj[4] = {j, j, j - 1, j + 1};
    for (int n = 0; n < 4; ++n) {
      if (ni[n] < 0 || ni[n] >= nx || nj[n] < 0 || nj[n] >= ny) continue;
      const size_t d = size_t(nj[n]) * nx + ni[n];
      if (!std::isnan((*z)[d])) continue;
      (*z)[d] = (*z)[c];
      queue.push_back(d);
    }
  }
  return missing;
}

Status read_text_file(const std::string& path, uint64_t max_bytes, std::string* out) {
  struct stat st;
  if (stat(path.c_str(), &st) != 0) return Status::IOError(path + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) return Status::IOError(path + ": not a regular file");
  if (uint64_t(st.st_size) > max_bytes)
    return Status::InvalidArgument(path + ": " + std::to_string(st.st_size >> 20) +
                                   " MiB of text, more than --memory allows for the surface");
  std::ifstream in(path, std::ios::binary);
  out->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) return Status::IOError(path + ": read error");
  return Status::Ok();
}

Status load_rfile_surface(const std::string& path, uint64_t max_bytes,
                          std::unique_ptr<Surface>* out) {
  RfileHeader h;
  WEAVER_RETURN_IF_ERROR(read_rfile_header(path, &h));
  const RfileBlock& t = h.blocks[0];
  if (Surface::bytes_for(t.ni, t.nj) > max_bytes)
    return Status::InvalidArgument(path + ": its topography needs more than --memory allows");
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status::IOError(path + ": " + std::strerror(errno));
  // The block is i-major (x): the surface's grid is j-major (y rows).
  std::vector<double> row(t.nj);
  std::vector<float> z(size_t(t.ni) * t.nj);
  Status st;
  for (int i = 0; i < t.ni && st.ok(); ++i) {
    for (int j = 0; j < t.nj && st.ok(); ++j) {
      st = read_rfile_column(fd, h, 0, i, j, &row[j]);
      if (st.ok() && !std::isfinite(row[j]))
        st = Status::Corruption(path + ": a topography value that is not a number");
      if (st.ok()) z[size_t(j) * t.ni + i] = float(row[j] == kRfileNoData ? NAN : row[j]);
    }
  }
  ::close(fd);
  WEAVER_RETURN_IF_ERROR(st);
  const uint64_t filled = fill_nodata(t.ni, t.nj, &z);
  if (filled == z.size()) return Status::Corruption(path + ": its topography has no data at all");
  *out = Surface::from_grid(t.ni, t.nj, 0, 0, t.hh, t.hh, std::move(z));
  (*out)->filled = filled;
  return Status::Ok();
}

// The raster in degrees, resampled onto the frame's metres at its own
// spacing (its north spacing in metres on both axes).
std::unique_ptr<Surface> resample_lonlat(const AscRaster& r, const GeoFrame& geo,
                                         uint64_t max_cells, uint64_t* filled) {
  const GeoTransform t(geo);
  double lo[2] = {HUGE_VAL, HUGE_VAL}, hi[2] = {-HUGE_VAL, -HUGE_VAL};
  const double lons[2] = {r.xll, r.xll + (r.ncols - 1) * r.dx};
  const double lats[2] = {r.yll, r.yll + (r.nrows - 1) * r.dy};
  for (int s = 0; s <= 16; ++s) {
    for (int e = 0; e < 2; ++e) {
      double x, y;
      const double f = s / 16.0;
      t.to_frame(lons[e], lats[0] + f * (lats[1] - lats[0]), &x, &y);
      lo[0] = std::min(lo[0], x), hi[0] = std::max(hi[0], x);
      lo[1] = std::min(lo[1], y), hi[1] = std::max(hi[1], y);
      t.to_frame(lons[0] + f * (lons[1] - lons[0]), lats[e], &x, &y);
      lo[0] = std::min(lo[0], x), hi[0] = std::max(hi[0], x);
      lo[1] = std::min(lo[1], y), hi[1] = std::max(hi[1], y);
    }
  }
  double step = r.dy * 111320.0;
  auto count = [&](int a) { return int(std::ceil((hi[a] - lo[a]) / step)) + 1; };
  while (uint64_t(count(0)) * count(1) > max_cells) step *= 1.25;
  const int nx = std::max(2, count(0)), ny = std::max(2, count(1));
  std::vector<float> z(size_t(nx) * ny);
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      double lon, lat;
      t.to_geo(lo[0] + i * step, lo[1] + j * step, &lon, &lat);
      const double u = (lon - r.xll) / r.dx, v = (lat - r.yll) / r.dy;
      float& out = z[size_t(j) * nx + i];
      if (!(u >= 0 && u <= r.ncols - 1 && v >= 0 && v <= r.nrows - 1)) {
        out = NAN;
        continue;
      }
      const int c = std::min(int(u), r.ncols - 2), w = std::min(int(v), r.nrows - 2);
      const double a = u - c, b = v - w;
      const auto g = [&](int cc, int rr) { return double(r.z[size_t(rr) * r.ncols + cc]); };
      out = float((1 - b) * ((1 - a) * g(c, w) + a * g(c + 1, w)) +
                  b * ((1 - a) * g(c, w + 1) + a * g(c + 1, w + 1)));
    }
  }
  *filled = fill_nodata(nx, ny, &z);
  return Surface::from_grid(nx, ny, lo[0], lo[1], step, step, std::move(z));
}

}  // namespace

Status parse_asc(const std::string& text, const std::string& what, uint64_t max_cells,
                 AscRaster* r) {
  *r = AscRaster{};
  std::istringstream in(text);
  double nodata = -9999, cellsize = 0, dx = 0, dy = 0, x = NAN, y = NAN;
  bool x_centre = false, y_centre = false;
  std::string first_value;
  for (std::string key; in >> key;) {
    std::string k = key;
    for (char& ch : k) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    if (!k.empty() && (std::isdigit(static_cast<unsigned char>(k[0])) || k[0] == '-' ||
                       k[0] == '+' || k[0] == '.')) {
      first_value = key;
      break;
    }
    std::string value;
    if (!(in >> value))
      return Status::Corruption(what + ": header keyword '" + key + "' has no value");
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    if (end == value.c_str() || *end != '\0' || !std::isfinite(v))
      return Status::Corruption(what + ": header '" + key + "' has value '" + value +
                                "', not a number");
    if (k == "ncols" || k == "nrows") {
      if (v != std::floor(v) || v < 2 || v > 1e8)
        return Status::Corruption(what + ": " + key + " " + value + " (a whole number >= 2)");
      (k == "ncols" ? r->ncols : r->nrows) = int(v);
    } else if (k == "xllcorner" || k == "xllcenter") {
      x = v, x_centre = k == "xllcenter";
    } else if (k == "yllcorner" || k == "yllcenter") {
      y = v, y_centre = k == "yllcenter";
    } else if (k == "cellsize") {
      cellsize = v;
    } else if (k == "dx") {
      dx = v;
    } else if (k == "dy") {
      dy = v;
    } else if (k == "nodata_value") {
      nodata = v;
    } else {
      return Status::Corruption(what + ": unknown header keyword '" + key + "'");
    }
  }
  if (r->ncols == 0 || r->nrows == 0) return Status::Corruption(what + ": no ncols or nrows");
  if (std::isnan(x) || std::isnan(y))
    return Status::Corruption(what + ": no xllcorner/xllcenter or yllcorner/yllcenter");
  r->dx = dx > 0 ? dx : cellsize;
  r->dy = dy > 0 ? dy : cellsize;
  if (!(r->dx > 0) || !(r->dy > 0))
    return Status::Corruption(what + ": no positive cellsize (or dx, dy)");
  if (uint64_t(r->ncols) * r->nrows > max_cells)
    return Status::InvalidArgument(what + ": " + std::to_string(r->ncols) + " x " +
                                   std::to_string(r->nrows) +
                                   " cells, more than --memory allows for the surface");
  r->xll = x_centre ? x : x + r->dx / 2;
  r->yll = y_centre ? y : y + r->dy / 2;
  r->z.resize(size_t(r->ncols) * r->nrows);
  // Rows come from the north: row 0 of the file is the last of the grid.
  for (size_t n = 0; n < r->z.size(); ++n) {
    std::string word;
    if (n == 0 && !first_value.empty()) {
      word = first_value;
    } else if (!(in >> word)) {
      return Status::Corruption(what + ": " + std::to_string(n) + " values of " +
                                std::to_string(r->z.size()) + " (truncated)");
    }
    char* end = nullptr;
    const double v = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0' || std::isnan(v))
      return Status::Corruption(what + ": value " + std::to_string(n + 1) + " is '" + word + "'");
    const size_t row = r->nrows - 1 - n / r->ncols, col = n % r->ncols;
    float& out = r->z[row * r->ncols + col];
    if (v == nodata) {
      out = NAN;
    } else if (!std::isfinite(v) || std::abs(v) > 1e5) {
      return Status::Corruption(what + ": value " + std::to_string(n + 1) + " is " + word +
                                " m (no ground is that high or deep)");
    } else {
      out = float(v);
    }
  }
  std::string extra;
  if (in >> extra) return Status::Corruption(what + ": more values than ncols x nrows");
  return Status::Ok();
}

Status parse_surface_source(const std::string& text, SurfaceSource* out) {
  out->text = text;
  if (text == "flat") return Status::Ok();
  for (const char* kind : {"rfile:", "asc:"}) {
    if (text.rfind(kind, 0) == 0 && text.size() > std::strlen(kind)) return Status::Ok();
  }
  return Status::InvalidArgument("--surface '" + text + "': flat, rfile:PATH or asc:PATH");
}

Status load_surface(const SurfaceSource& s, const GeoFrame* geo, uint64_t max_bytes,
                    std::unique_ptr<Surface>* out) {
  out->reset();
  if (s.flat()) return Status::Ok();
  if (s.text.rfind("rfile:", 0) == 0) return load_rfile_surface(s.text.substr(6), max_bytes, out);
  const std::string path = s.text.substr(4);
  std::string text;
  WEAVER_RETURN_IF_ERROR(read_text_file(path, max_bytes, &text));
  AscRaster r;
  const uint64_t max_cells = max_bytes / 16;
  WEAVER_RETURN_IF_ERROR(parse_asc(text, path, max_cells, &r));
  text = std::string();
  if (s.crs == SurfaceCrs::kLonLat) {
    if (geo == nullptr)
      return Status::InvalidArgument(
          "--surface-crs lonlat needs --origin-geo (or a model that "
          "places itself on the Earth)");
    if (fill_nodata(r.ncols, r.nrows, &r.z) == r.z.size())
      return Status::Corruption(path + ": no data at all");
    uint64_t filled = 0;
    *out = resample_lonlat(r, *geo, max_cells, &filled);
    (*out)->filled = filled;
    return Status::Ok();
  }
  // The raster's x (east) is the frame's y, its y (north) the frame's x.
  std::vector<float> z(r.z.size());
  for (int row = 0; row < r.nrows; ++row)
    for (int col = 0; col < r.ncols; ++col)
      z[size_t(col) * r.nrows + row] = r.z[size_t(row) * r.ncols + col];
  const uint64_t filled = fill_nodata(r.nrows, r.ncols, &z);
  if (filled == z.size()) return Status::Corruption(path + ": no data at all");
  *out = Surface::from_grid(r.nrows, r.ncols, r.yll, r.xll, r.dy, r.dx, std::move(z));
  (*out)->filled = filled;
  return Status::Ok();
}

}  // namespace weaver
