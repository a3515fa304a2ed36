#include "modeldb/grid_import.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

namespace weaver {
namespace {

// Octants of one block of a grid, a side: blocks of 32^3 points read in
// 32 x 32 rows keep a block's reads near 400 KB.
constexpr int kGridBlockLevels = 5;

class GridBlockReader {
 public:
  GridBlockReader(const GridPlan& g, int fd, std::string path)
      : g_(g), fd_(fd), path_(std::move(path)) {}

  // The material of every octant of block [lo, hi) (in cells), into
  // out[((k - lo.z) * side + (j - lo.y)) * side + (i - lo.x)].
  Status read(const std::array<uint32_t, 3>& lo, const std::array<uint32_t, 3>& hi, uint32_t side,
              std::vector<ModelValues>* out) {
    const int n[3] = {g_.s.nx, g_.s.ny, g_.s.nz};
    const double d[3] = {g_.s.dx, g_.s.dy, g_.s.dz};
    for (int a = 0; a < 3; ++a) {
      cell_index_[a].clear();
      cell_frac_[a].clear();
      for (uint32_t c = lo[a]; c < hi[a]; ++c) {
        const double t = std::clamp(c * g_.edge_m / d[a], 0.0, double(n[a] - 1));
        const int i = std::min(static_cast<int>(t), n[a] - 2);
        cell_index_[a].push_back(i);
        cell_frac_[a].push_back(t - i);
      }
      first_[a] = cell_index_[a].front();
      span_[a] = cell_index_[a].back() + 2 - first_[a];
    }
    WEAVER_RETURN_IF_ERROR(read_rows());
    out->assign(size_t{side} * side * side, ModelValues{});
    for (uint32_t k = 0; k < hi[2] - lo[2]; ++k)
      for (uint32_t j = 0; j < hi[1] - lo[1]; ++j)
        for (uint32_t i = 0; i < hi[0] - lo[0]; ++i)
          (*out)[(size_t{k} * side + j) * side + i] = interpolate(i, j, k);
    return Status::Ok();
  }

 private:
  Status read_rows() {
    rows_.resize(size_t(span_[0]) * span_[1] * span_[2] * 3);
    for (int z = 0; z < span_[2]; ++z) {
      for (int y = 0; y < span_[1]; ++y) {
        const uint64_t point =
            (uint64_t(first_[2] + z) * g_.s.ny + (first_[1] + y)) * g_.s.nx + first_[0];
        float* row = &rows_[(size_t(z) * span_[1] + y) * span_[0] * 3];
        const size_t bytes = size_t(span_[0]) * 12;
        if (::pread(fd_, row, bytes, static_cast<off_t>(g_.data + point * 12)) !=
            static_cast<ssize_t>(bytes)) {
          return Status::IOError(path_ + ": cannot read the grid data");
        }
        for (int x = 0; x < span_[0]; ++x) {
          const ModelValues v{row[3 * x], row[3 * x + 1], row[3 * x + 2], 0, 0};
          if (const int bad = bad_model_field(v, 3); bad >= 0) {
            return bad_model_value(path_ + ": grid point " + std::to_string(point + x), v, bad);
          }
        }
      }
    }
    return Status::Ok();
  }

  ModelValues interpolate(uint32_t i, uint32_t j, uint32_t k) const {
    const int base[3] = {cell_index_[0][i] - first_[0], cell_index_[1][j] - first_[1],
                         cell_index_[2][k] - first_[2]};
    const double f[3] = {cell_frac_[0][i], cell_frac_[1][j], cell_frac_[2][k]};
    double sum[3] = {0, 0, 0};
    for (int c = 0; c < 8; ++c) {
      const double w =
          ((c & 1) ? f[0] : 1 - f[0]) * ((c & 2) ? f[1] : 1 - f[1]) * ((c & 4) ? f[2] : 1 - f[2]);
      if (w == 0) continue;
      const size_t at =
          ((size_t(base[2] + ((c >> 2) & 1)) * span_[1] + base[1] + ((c >> 1) & 1)) * span_[0] +
           base[0] + (c & 1)) *
          3;
      for (int v = 0; v < 3; ++v) sum[v] += w * rows_[at + v];
    }
    return {float(sum[0]), float(sum[1]), float(sum[2]), 0, 0};
  }

  const GridPlan& g_;
  int fd_;
  std::string path_;
  std::vector<int> cell_index_[3];
  std::vector<double> cell_frac_[3];
  int first_[3] = {0, 0, 0}, span_[3] = {0, 0, 0};
  std::vector<float> rows_;
};

}  // namespace

Status plan_grid(const std::string& path, GridPlan* g, ModelInfo* info) {
  WEAVER_RETURN_IF_ERROR(read_grid_header(path, &g->s, &g->data));
  const GridSpec& s = g->s;
  g->edge_m = std::min({s.dx, s.dy, s.dz});
  const int n[3] = {s.nx, s.ny, s.nz};
  const double d[3] = {s.dx, s.dy, s.dz};
  uint32_t most = 1;
  for (int a = 0; a < 3; ++a) {
    g->cells[a] = static_cast<uint32_t>(std::floor((n[a] - 1) * d[a] / g->edge_m + 1e-9)) + 1;
    most = std::max(most, g->cells[a]);
  }
  while ((uint32_t{1} << g->level) < most) ++g->level;
  if (g->level > kMaxLevel) {
    return Status::InvalidArgument(path +
                                   ": the grid needs more than weaver's 2^20 octants a side");
  }
  info->tick_m = g->edge_m * (uint64_t{1} << g->level) / kRootEdge;
  // Octant i is centred on grid point i (on the smallest spacing's axis).
  info->origin_m = {s.x0 - g->edge_m / 2, s.y0 - g->edge_m / 2, s.z0 - g->edge_m / 2};
  for (int a = 0; a < 3; ++a) info->extent_m[a] = g->cells[a] * g->edge_m;
  return Status::Ok();
}

Status import_grid(const GridPlan& g, const std::string& path, uint64_t* read,
                   const ModelEmit& emit) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status::NotFound(path + ": cannot open the grid model file");
  GridBlockReader reader(g, fd, path);
  const int block_level = std::max(0, g.level - kGridBlockLevels);
  const uint32_t side = uint32_t{1} << (g.level - block_level);  // cells a block
  const uint32_t cell_ticks = octant_edge(g.level);
  std::vector<ModelValues> values;
  // Blocks in Z-order, those that meet the grid's box.
  std::function<Status(const Octant&)> visit = [&](const Octant& b) -> Status {
    const uint32_t shift = kMaxLevel - g.level;
    const std::array<uint32_t, 3> lo = {b.x >> shift, b.y >> shift, b.z >> shift};
    if (lo[0] >= g.cells[0] || lo[1] >= g.cells[1] || lo[2] >= g.cells[2]) return Status::Ok();
    if (b.level < block_level) {
      for (int c = 0; c < 8; ++c) WEAVER_RETURN_IF_ERROR(visit(octant_child(b, c)));
      return Status::Ok();
    }
    std::array<uint32_t, 3> hi;
    for (int a = 0; a < 3; ++a) hi[a] = std::min(lo[a] + side, g.cells[a]);
    WEAVER_RETURN_IF_ERROR(reader.read(lo, hi, side, &values));
    for (uint64_t m = 0; m < uint64_t{side} * side * side; ++m) {
      const Coord c = morton_decode(m);
      if (lo[0] + c.x >= hi[0] || lo[1] + c.y >= hi[1] || lo[2] + c.z >= hi[2]) continue;
      const Octant o{b.x + c.x * cell_ticks, b.y + c.y * cell_ticks, b.z + c.z * cell_ticks,
                     static_cast<uint8_t>(g.level)};
      ++*read;
      WEAVER_RETURN_IF_ERROR(emit(o, values[(size_t(c.z) * side + c.y) * side + c.x]));
    }
    return Status::Ok();
  };
  const Status st = visit(octant_root());
  ::close(fd);
  return st;
}

namespace {

// Consecutive records gathered into one write (an xyz file in grid order
// writes a megabyte at a time; any other order, a record at a time).
class RecordWriter {
 public:
  RecordWriter(int fd, uint64_t data) : fd_(fd), data_(data) {}
  Status put(uint64_t index, const float v[3]) {
    if (!buf_.empty() && (index != first_ + buf_.size() / 3 || buf_.size() >= (1u << 18))) {
      WEAVER_RETURN_IF_ERROR(flush());
    }
    if (buf_.empty()) first_ = index;
    buf_.insert(buf_.end(), v, v + 3);
    return Status::Ok();
  }
  Status flush() {
    const size_t bytes = buf_.size() * sizeof(float);
    const off_t at = static_cast<off_t>(data_ + first_ * 12);
    if (!buf_.empty() && ::pwrite(fd_, buf_.data(), bytes, at) != static_cast<ssize_t>(bytes)) {
      return Status::IOError("cannot write the grid file");
    }
    buf_.clear();
    return Status::Ok();
  }

 private:
  int fd_;
  uint64_t data_, first_ = 0;
  std::vector<float> buf_;
};

// The first record left zero (no line gave it), or Ok.
Status find_missing_point(int fd, uint64_t data, const GridSpec& s, const std::string& xyz) {
  const uint64_t n = uint64_t(s.nx) * s.ny * s.nz;
  std::vector<float> buf(3 << 16);
  for (uint64_t first = 0; first < n; first += buf.size() / 3) {
    const uint64_t count = std::min<uint64_t>(buf.size() / 3, n - first);
    if (::pread(fd, buf.data(), count * 12, static_cast<off_t>(data + first * 12)) !=
        static_cast<ssize_t>(count * 12)) {
      return Status::IOError(xyz + ": cannot read back the grid it was written to");
    }
    for (uint64_t i = 0; i < count; ++i) {
      if (buf[3 * i] != 0) continue;
      const uint64_t p = first + i;
      char at[160];
      std::snprintf(at, sizeof at, ": no line gives grid point (%g, %g, %g) (and one is repeated)",
                    s.x0 + double(p % s.nx) * s.dx, s.y0 + double(p / s.nx % s.ny) * s.dy,
                    s.z0 + double(p / s.nx / s.ny) * s.dz);
      return Status::Corruption(xyz + at);
    }
  }
  return Status::Ok();
}

Status fill_grid(int fd, const std::string& xyz_path, const XyzGrid& grid) {
  const GridSpec& s = grid.spec;
  char header[256];
  const int len = std::snprintf(header, sizeof header,
                                "weaver-grid 1\n%d %d %d\n%.17g %.17g %.17g\n%.17g %.17g %.17g\n",
                                s.nx, s.ny, s.nz, s.x0, s.y0, s.z0, s.dx, s.dy, s.dz);
  const uint64_t data = static_cast<uint64_t>(len);
  const uint64_t n = uint64_t(s.nx) * s.ny * s.nz;
  if (::pwrite(fd, header, data, 0) != len ||
      ::ftruncate(fd, static_cast<off_t>(data + n * 12)) != 0) {
    return Status::IOError(xyz_path + ": cannot write the grid it is read into");
  }
  RecordWriter out(fd, data);
  WEAVER_RETURN_IF_ERROR(for_each_xyz_point(
      xyz_path, grid, [&](uint64_t index, const float v[3]) { return out.put(index, v); }));
  WEAVER_RETURN_IF_ERROR(out.flush());
  return find_missing_point(fd, data, s, xyz_path);
}

}  // namespace

Status write_xyz_as_grid(const std::string& xyz_path, const XyzGrid& grid,
                         const std::string& grid_path) {
  const int fd = ::open(grid_path.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Status::IOError(grid_path + ": cannot create the grid file");
  const Status st = fill_grid(fd, xyz_path, grid);
  ::close(fd);
  if (!st.ok()) ::unlink(grid_path.c_str());
  return st;
}

}  // namespace weaver
