// An SW4 rfile (model/rfile.h) as a velocity model, sampled as SW4's
// MaterialRfile samples it: the block is the deepest whose top z0 lies at or
// above the point (the first material block above them all); the cell is
// trunc((x - 0) / hh) along each axis, held to the block's last cell; the
// value is trilinear in that cell.  Before sampling, a -999 (no data) takes
// the first valid value below it in its column; a column with no valid
// value takes the top value of the block below at the nearest-below point
// (trunc of its coordinate), as SW4's fill does.  Points outside the file's
// box are moved to its nearest point first (construct says so, or refuses
// with --outside error).
//
// The model's z is SW4's: metres down from sea level (negative above it).
// The file is never read whole: each thread keeps a cache of filled columns
// (all levels of one (i, j) of one block), sized from `memory`; construct's
// subtrees touch a few thousand columns each.
//
// Store as sampled: a mesh built from an rfile samples the file itself at
// each leaf's points (so hh, hv, and any spacing that is no power-of-two
// part of the root, stay as SW4 sees them); nothing is rounded to ticks.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "model/rfile.h"
#include "model/rfile_vs_tiles.h"
#include "model/velocity_model.h"
#include "util/memory_budget.h"

namespace weaver {

class RfileModel final : public VelocityModel {
 public:
  // Opens path (header checked; the bottom block scanned once for a column
  // with no valid value, which nothing could fill).  `memory` is shared by
  // the column caches of up to `threads` threads.
  static Status open(const std::string& path, MemoryBudget memory, int threads,
                     std::unique_ptr<RfileModel>* out);
  ~RfileModel() override;

  const RfileHeader& header() const { return h_; }
  const std::string& path() const { return path_; }
  // The model's box: x in [0, x_extent], y in [0, y_extent], z (down from
  // sea level) in [z_top, z_bottom].
  double x_extent() const { return h_.blocks[0].x_extent(); }
  double y_extent() const { return h_.blocks[0].y_extent(); }
  double z_top() const { return h_.blocks[1].z0; }
  double z_bottom() const { return h_.blocks.back().bottom(); }
  // The first read error met while sampling (at() answers no material then).
  Status error() const;

  Material at(double x, double y, double z) const override;
  // The values at the points (xs[a], ys[b], zs[c]) of a lattice, each list
  // ascending, as at() finds each point, to the bit, into
  // out[(c * ny + b) * nx + a]: each block's columns are looked up once for
  // the lattice, not four times a point (model import's path).
  void lattice_at(const double* xs, int nx, const double* ys, int ny, const double* zs, int nz,
                  Material* out) const;
  // Vs alone: the same cell and weights, one component interpolated.
  float vs_at(double x, double y, double z) const override;
  // vs_at at each point, each column placed across once and its corner
  // columns looked up once a block (construct's lattices, under a ground
  // or not).
  void vs_on_columns(const double* xs, const double* ys, const double* zs, int n,
                     float* out) const override;
  void vs_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                     float* out) const override;
  // From the least and greatest Vs of tiles of the grid (rfile_vs_tiles.h),
  // built on the first call (a pass over the file).
  bool vs_bounds(const double lo[3], const double hi[3], float* vs_lo, float* vs_hi) const override;
  bool has_q() const override { return h_.has_q(); }
  // Sides of [0, domain_m] (x, y; z counted down from sea level) past the
  // file's box.
  std::string outside(const std::array<double, 3>& domain_m) const override;
  std::string geo() const override;
  std::string projection() const override { return h_.proj; }
  std::string describe() const override;

 private:
  struct Cache;
  static constexpr int kLatticeMost = 8;
  RfileModel() = default;
  Cache& cache() const;
  // Column (i, j) of block b, filled, in the calling thread's cache: valid
  // until the next call on this thread.
  // A miss reads kRunColumns columns from j on at once (one read: they lie
  // one after another in the file): the next lookups want them, both the
  // import's lattices and construct's points (measured: 0.25 Hz from the
  // 1.09 GB test rfile, construct 10.5 s against 11.1-11.9 s one by one).
  const double* column(Cache& c, int b, int i, int j) const;
  bool corner_columns(Cache& c, int b, int i0, int j0, const double* (&cols)[2][2]) const;
  // Fills the no-data levels of column (i, j) of block b, as decoded, in
  // place: a donor's lookup may take col's slot, and col is all written
  // after it.
  void fill_column(Cache& c, int b, int i, int j, double* col) const;
  // The lattice points of one block (zs all in it): lattice_at's work.
  void lattice_in_block(Cache& c, int b, const double* xs, int nx, const double* ys, int ny,
                        const double* zs, int nz, Material* out) const;
  void fail(const Status& s) const;
  // The cell of (x, y, z) as SW4 finds it: its block, first point and weights.
  struct Cell {
    int block, i0, j0, k0;
    double wx, wy, wz;
  };
  Cell cell_of(double x, double y, double z) const;
  // The block a depth (held to the box) falls in, as SW4 finds it.
  int block_of(double z) const;

  std::string path_;
  RfileHeader h_;
  int fd_ = -1;
  size_t stride_ = 0;    // doubles a cached column holds: the most nk x nc of any block
  size_t slots_ = 0;     // a cache's columns (a power of two)
  uint64_t serial_ = 0;  // tells this model's caches from a former one's at the same address
  mutable std::mutex mu_;
  mutable std::unordered_map<std::thread::id, std::unique_ptr<Cache>> caches_;
  mutable std::atomic<bool> failed_{false};
  mutable std::once_flag tiles_once_;
  mutable RfileVsTiles tiles_;
  mutable Status error_;
};

}  // namespace weaver
