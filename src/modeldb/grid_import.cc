#include "modeldb/grid_import.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <functional>
#include <vector>

#include "model/block_merge.h"

namespace weaver {
namespace {

// The most levels of a block (2^7 = 128 points a side, 2M points; two are
// read at once, 52 MB): each row is one pread, so larger blocks read the
// grid in fewer, longer reads.
constexpr int kMaxGridBlockLevels = 7;
// Bytes a block holds a point: its rows as read (12) and some slack, twice
// over (two blocks are read at once).
constexpr uint64_t kGridBlockBytesPerPoint = 28;
// A read block is merged in parts of 2^5 = 32 points a side (model/
// block_merge.h): their values (640 KB) stay in the cache while they merge.
constexpr int kMergeLevels = 5;

// The deepest block whose memory fits in the share, at least 2^3 points a side.
int grid_block_levels(const GridPlan& g, MemoryBudget memory) {
  int levels = kMaxGridBlockLevels;
  while (levels > 3 && (uint64_t{1} << (3 * levels)) * kGridBlockBytesPerPoint > memory.bytes()) {
    --levels;
  }
  return std::max(1, std::min(levels, g.level));
}

// The bits of v spread to every third bit: v's part of a Morton code.
uint64_t spread3(uint32_t v) { return morton_encode(v, 0, 0); }

class GridBlockReader {
 public:
  GridBlockReader(const GridPlan& g, int fd, std::string path)
      : g_(g), fd_(fd), path_(std::move(path)) {}

  // Reads the rows of block [lo, hi) (in cells).
  Status read(const std::array<uint32_t, 3>& lo, const std::array<uint32_t, 3>& hi) {
    const int n[3] = {g_.s.nx, g_.s.ny, g_.s.nz};
    const double d[3] = {g_.s.dx, g_.s.dy, g_.s.dz};
    lo_ = lo;
    for (int a = 0; a < 3; ++a) {
      cell_index_[a].clear();
      cell_frac_[a].clear();
      code_[a].clear();
      for (uint32_t c = lo[a]; c < hi[a]; ++c) {
        const double t = std::clamp(c * g_.edge_m / d[a], 0.0, double(n[a] - 1));
        const int i = std::min(static_cast<int>(t), n[a] - 2);
        cell_index_[a].push_back(i);
        cell_frac_[a].push_back(t - i);
        // The cell's part of its Morton code in its merge part.
        code_[a].push_back(spread3((c - lo[a]) & ((1u << kMergeLevels) - 1)) << a);
      }
      first_[a] = cell_index_[a].front();
      span_[a] = cell_index_[a].back() + 2 - first_[a];
    }
    return read_rows();
  }

  // The material of every octant of part [lo, hi) (in cells, inside the
  // block read last) into the part's values, by Morton order in the part;
  // cells past hi (outside the grid) are marked absent.
  void fill(const std::array<uint32_t, 3>& lo, const std::array<uint32_t, 3>& hi,
            BlockMerger* part) const {
    std::vector<ModelValues>& values = part->values();
    std::vector<uint8_t>& present = part->present();
    std::fill(present.begin(), present.end(), 0);
    for (uint32_t k = lo[2] - lo_[2]; k < hi[2] - lo_[2]; ++k)
      for (uint32_t j = lo[1] - lo_[1]; j < hi[1] - lo_[1]; ++j) {
        const uint64_t jk = code_[1][j] | code_[2][k];
        for (uint32_t i = lo[0] - lo_[0]; i < hi[0] - lo_[0]; ++i) {
          values[code_[0][i] | jk] = interpolate(i, j, k);
          present[code_[0][i] | jk] = 1;
        }
      }
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
        // Positive and finite (NaN fails the compare); bad_model_field's
        // rule, a row at a time, and it names the field of the first miss.
        bool ok = true;
        for (size_t i = 0; i < size_t(span_[0]) * 3; ++i) ok &= row[i] > 0 && row[i] <= FLT_MAX;
        for (int x = 0; !ok && x < span_[0]; ++x) {
          const ModelValues v{row[3 * x], row[3 * x + 1], row[3 * x + 2], 0, 0};
          if (const int bad = bad_model_field(v, 3); bad >= 0) {
            return bad_model_value(path_ + ": grid point " + std::to_string(point + x), v, bad);
          }
        }
      }
    }
    return Status::Ok();
  }

  const float* point(int x, int y, int z) const {
    return &rows_[((size_t(z) * span_[1] + y) * span_[0] + x) * 3];
  }

  ModelValues interpolate(uint32_t i, uint32_t j, uint32_t k) const {
    const int base[3] = {cell_index_[0][i] - first_[0], cell_index_[1][j] - first_[1],
                         cell_index_[2][k] - first_[2]};
    const double f[3] = {cell_frac_[0][i], cell_frac_[1][j], cell_frac_[2][k]};
    if ((f[0] == 0 || f[0] == 1) && (f[1] == 0 || f[1] == 1) && (f[2] == 0 || f[2] == 1)) {
      // On a grid point (every axis at the smallest spacing): no weights.
      const float* p = point(base[0] + int(f[0]), base[1] + int(f[1]), base[2] + int(f[2]));
      return {p[0], p[1], p[2], 0, 0};
    }
    double sum[3] = {0, 0, 0};
    for (int c = 0; c < 8; ++c) {
      const double w =
          ((c & 1) ? f[0] : 1 - f[0]) * ((c & 2) ? f[1] : 1 - f[1]) * ((c & 4) ? f[2] : 1 - f[2]);
      if (w == 0) continue;
      const float* p = point(base[0] + (c & 1), base[1] + ((c >> 1) & 1), base[2] + ((c >> 2) & 1));
      for (int v = 0; v < 3; ++v) sum[v] += w * p[v];
    }
    return {float(sum[0]), float(sum[1]), float(sum[2]), 0, 0};
  }

  const GridPlan& g_;
  int fd_;
  std::string path_;
  std::vector<int> cell_index_[3];
  std::vector<double> cell_frac_[3];
  std::array<uint32_t, 3> lo_{};   // the block read last
  std::vector<uint64_t> code_[3];  // the cell's part of its Morton code in its merge part
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

namespace {

// The grid's octants to the merger, in key order: blocks in Z-order, those
// that meet the grid's box, x-neighbour pairs read together (rows twice as
// long, half the preads), each block merged a part at a time.
class GridImport {
 public:
  GridImport(const GridPlan& g, int fd, const std::string& path, MemoryBudget memory,
             MaterialMerger& merger)
      : g_(g),
        reader_(g, fd, path),
        levels_(grid_block_levels(g, memory)),
        part_(std::min(levels_, kMergeLevels)),
        merger_(merger) {}

  Status run(uint64_t* read) {
    const Status st = visit(octant_root());
    *read = read_;
    return st;
  }

 private:
  // The grid cells of octant o, `cells` a side: [lo, hi), false when o lies
  // past the grid.
  bool cells_of(const Octant& o, uint32_t cells, std::array<uint32_t, 3>* lo,
                std::array<uint32_t, 3>* hi) const {
    const uint32_t shift = kMaxLevel - g_.level;
    *lo = {o.x >> shift, o.y >> shift, o.z >> shift};
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
      (*hi)[a] = std::min((*lo)[a] + cells, g_.cells[a]);
      inside = inside && (*lo)[a] < g_.cells[a];
    }
    return inside;
  }

  Status visit(const Octant& b) {
    const int block_level = g_.level - levels_;
    std::array<uint32_t, 3> lo, hi;
    if (!cells_of(b, uint32_t{1} << (g_.level - b.level), &lo, &hi)) return Status::Ok();
    if (b.level == block_level) return read_and_merge(b, 1);  // the grid is one block
    if (b.level + 1 < block_level) {
      for (int c = 0; c < 8; ++c) WEAVER_RETURN_IF_ERROR(visit(octant_child(b, c)));
      return Status::Ok();
    }
    for (int c = 0; c < 8; c += 2) WEAVER_RETURN_IF_ERROR(read_and_merge(octant_child(b, c), 2));
    return Status::Ok();
  }

  // Reads block `first` and, for count 2, its x-neighbour (children 2i and
  // 2i + 1 of one parent: Morton neighbours) in one go, and merges them.
  Status read_and_merge(const Octant& first, int count) {
    const uint32_t side = uint32_t{1} << levels_;
    std::array<uint32_t, 3> lo, hi;
    if (!cells_of(first, side, &lo, &hi)) return Status::Ok();
    hi[0] = std::min(lo[0] + count * side, g_.cells[0]);
    WEAVER_RETURN_IF_ERROR(reader_.read(lo, hi));
    read_ += uint64_t{hi[0] - lo[0]} * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    WEAVER_RETURN_IF_ERROR(merge(first));
    Octant next = first;
    next.x += octant_edge(first);
    return count == 2 && next.x < kRootEdge ? merge(next) : Status::Ok();
  }

  // A block's parts in Z-order, merged one after another.
  Status merge(const Octant& p) {
    std::array<uint32_t, 3> lo, hi;
    if (!cells_of(p, part_.side(), &lo, &hi)) return Status::Ok();
    if (p.level < g_.level - part_.levels()) {
      for (int c = 0; c < 8; ++c) WEAVER_RETURN_IF_ERROR(merge(octant_child(p, c)));
      return Status::Ok();
    }
    reader_.fill(lo, hi, &part_);
    return part_.merge_into(p, merger_);
  }

  const GridPlan& g_;
  GridBlockReader reader_;
  const int levels_;  // of a block
  BlockMerger part_;
  MaterialMerger& merger_;
  uint64_t read_ = 0;
};

}  // namespace

Status import_grid(const GridPlan& g, const std::string& path, MemoryBudget memory, uint64_t* read,
                   MaterialMerger& merger) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status::NotFound(path + ": cannot open the grid model file");
  uint64_t n = 0;
  const Status st = GridImport(g, fd, path, memory, merger).run(&n);
  *read += n;
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
