#include "model/xyz_grid.h"

#include <fcntl.h>
#include <unistd.h>

#include <charconv>
#include <cmath>
#include <set>
#include <string_view>
#include <vector>

#include "util/read_decimal.h"

namespace weaver {
namespace {

constexpr size_t kChunk = 1 << 20;  // bytes read at a time; also the longest line
constexpr int kMaxPointsAnAxis = 100000;

// The lines of a file, a chunk at a time.
class LineReader {
 public:
  explicit LineReader(const std::string& path)
      : path_(path), fd_(::open(path.c_str(), O_RDONLY | O_CLOEXEC)) {}
  ~LineReader() {
    if (fd_ >= 0) ::close(fd_);
  }
  Status opened() const {
    return fd_ >= 0 ? Status::Ok() : Status::NotFound(path_ + ": cannot open the xyz model file");
  }
  // The next line (without its newline); *done at the end of the file.
  Status next(std::string_view* line, bool* done) {
    for (;;) {
      const size_t nl = buf_.find('\n', pos_);
      if (nl != std::string::npos) {
        *line = std::string_view(buf_).substr(pos_, nl - pos_);
        pos_ = nl + 1;
        ++number_;
        return Status::Ok();
      }
      if (eof_) {
        *done = pos_ == buf_.size();
        *line = std::string_view(buf_).substr(pos_);
        pos_ = buf_.size();
        if (!*done) ++number_;
        return Status::Ok();
      }
      buf_.erase(0, pos_);
      pos_ = 0;
      if (buf_.size() >= kChunk) {
        return Status::Corruption(path_ + ":" + std::to_string(number_ + 1) +
                                  ": a line longer than 1 MB");
      }
      const size_t had = buf_.size();
      buf_.resize(had + kChunk);
      const ssize_t n = ::read(fd_, buf_.data() + had, kChunk);
      if (n < 0) return Status::IOError(path_ + ": cannot read the xyz model file");
      buf_.resize(had + static_cast<size_t>(n));
      eof_ = n == 0;
    }
  }
  uint64_t line_number() const { return number_; }

 private:
  std::string path_;
  int fd_;
  std::string buf_;
  size_t pos_ = 0;
  bool eof_ = false;
  uint64_t number_ = 0;
};

Status bad_line(const std::string& path, uint64_t line, const std::string& what) {
  return Status::Corruption(path + ":" + std::to_string(line) + ": " + what);
}

// Parses `x y z vp vs rho` (sets *blank for a blank or comment line).
Status parse_point(std::string_view line, const std::string& path, uint64_t n, double v[6],
                   bool* blank) {
  line = line.substr(0, line.find('#'));
  const char* p = line.data();
  const char* end = p + line.size();
  int count = 0;
  for (;;) {
    while (p < end && (*p == ' ' || *p == '\t' || *p == '\r' || *p == ',')) ++p;
    if (p == end) break;
    if (count == 6) return bad_line(path, n, "more than 6 numbers (x y z vp vs rho)");
    const auto r = read_decimal(p, end, v[count]);
    if (r.ec != std::errc() ||
        (r.ptr < end && *r.ptr != ' ' && *r.ptr != '\t' && *r.ptr != '\r' && *r.ptr != ',')) {
      const char* w = p;
      while (w < end && *w != ' ' && *w != '\t') ++w;
      return bad_line(path, n, "'" + std::string(p, w) + "' is not a number");
    }
    p = r.ptr;
    ++count;
  }
  *blank = count == 0;
  if (*blank) return Status::Ok();
  if (count != 6) {
    return bad_line(path, n,
                    "a point is 'x y z vp vs rho', not " + std::to_string(count) + " numbers");
  }
  static const char* names[] = {"x", "y", "z", "Vp", "Vs", "density"};
  for (int f = 0; f < 6; ++f) {
    if (!std::isfinite(v[f]) || (f >= 3 && !(v[f] > 0))) {
      return bad_line(path, n,
                      std::string(names[f]) + " " + std::to_string(v[f]) +
                          (f >= 3 ? " must be positive and finite" : " must be finite"));
    }
  }
  return Status::Ok();
}

// The even spacing of an axis's sorted distinct values.
Status axis_of(const std::set<double>& values, const std::string& path, const char* axis, int* n,
               double* first, double* step) {
  *n = static_cast<int>(values.size());
  if (*n < 2) {
    return Status::Corruption(path + ": the grid needs at least 2 distinct " + axis + " values");
  }
  *first = *values.begin();
  *step = (*values.rbegin() - *first) / (*n - 1);
  int i = 0;
  for (double v : values) {
    if (std::abs(v - (*first + i * *step)) > 1e-3 * *step) {
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    ": %s values are not evenly spaced (%g where %g was due, spacing %g)", axis, v,
                    *first + i * *step, *step);
      return Status::Corruption(path + buf);
    }
    ++i;
  }
  return Status::Ok();
}

// Each point line of the file, parsed, with its line number.
template <typename Fn>
Status for_each_line_point(const std::string& path, Fn fn) {
  LineReader in(path);
  WEAVER_RETURN_IF_ERROR(in.opened());
  for (;;) {
    std::string_view line;
    bool done = false, blank = false;
    WEAVER_RETURN_IF_ERROR(in.next(&line, &done));
    if (done) return Status::Ok();
    double v[6];
    WEAVER_RETURN_IF_ERROR(parse_point(line, path, in.line_number(), v, &blank));
    if (!blank) WEAVER_RETURN_IF_ERROR(fn(in.line_number(), v));
  }
}

}  // namespace

Status scan_xyz_grid(const std::string& path, XyzGrid* out) {
  *out = XyzGrid{};
  std::set<double> axes[3];
  static const char* names[] = {"x", "y", "z"};
  WEAVER_RETURN_IF_ERROR(for_each_line_point(path, [&](uint64_t line, const double v[6]) {
    ++out->points;
    for (int a = 0; a < 3; ++a) {
      axes[a].insert(v[a]);
      if (axes[a].size() > kMaxPointsAnAxis) {
        return bad_line(path, line,
                        std::string("more than 100000 distinct ") + names[a] + " values");
      }
    }
    return Status::Ok();
  }));
  GridSpec& s = out->spec;
  WEAVER_RETURN_IF_ERROR(axis_of(axes[0], path, "x", &s.nx, &s.x0, &s.dx));
  WEAVER_RETURN_IF_ERROR(axis_of(axes[1], path, "y", &s.ny, &s.y0, &s.dy));
  WEAVER_RETURN_IF_ERROR(axis_of(axes[2], path, "z", &s.nz, &s.z0, &s.dz));
  const uint64_t want = uint64_t(s.nx) * s.ny * s.nz;
  if (out->points != want) {
    return Status::Corruption(path + ": " + std::to_string(out->points) + " points for a " +
                              std::to_string(s.nx) + " x " + std::to_string(s.ny) + " x " +
                              std::to_string(s.nz) + " grid (" + std::to_string(want) + ")");
  }
  return Status::Ok();
}

Status for_each_xyz_point(const std::string& path, const XyzGrid& grid, const XyzPointFn& fn) {
  const GridSpec& s = grid.spec;
  const double first[3] = {s.x0, s.y0, s.z0}, step[3] = {s.dx, s.dy, s.dz};
  const int n[3] = {s.nx, s.ny, s.nz};
  return for_each_line_point(path, [&](uint64_t line, const double v[6]) {
    uint64_t index = 0;
    for (int a = 2; a >= 0; --a) {
      const double i = std::round((v[a] - first[a]) / step[a]);
      // The file changed since the scan if a point is off the grid.
      if (!(i >= 0 && i < n[a]) || std::abs(v[a] - (first[a] + i * step[a])) > 1e-3 * step[a]) {
        return bad_line(path, line, "the point is off the grid the first pass found");
      }
      index = index * uint64_t(n[a]) + static_cast<uint64_t>(i);
    }
    const float values[3] = {float(v[3]), float(v[4]), float(v[5])};
    return fn(index, values);
  });
}

}  // namespace weaver
