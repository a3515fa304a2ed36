// A velocity model read from a model database (modeldb/model_table.h): the
// material at a point is the model octant holding it, found by the
// aggregate-hit (floor) query.  Points outside the model's box are clamped
// into it.  Safe to use from many threads at once (construct's workers):
// each thread gets its own table handle, with its own share of the memory,
// remembers the last octant it hit, and holds the octants of the box it was
// last focused on (modeldb/model_region.h), which answer without the table.
#pragma once

#include <array>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "model/material_merge.h"
#include "model/velocity_model.h"
#include "modeldb/model_region.h"
#include "modeldb/model_table.h"
#include "util/memory_budget.h"

namespace weaver {

class Database;
class BTree;

struct ModelHit {
  ModelValues values{};
  Octant octant;         // the model octant it came from
  bool clamped = false;  // the point lay outside the model's box
};

class DbModel final : public VelocityModel {
 public:
  // Opens the model table of the database in dir, read-only.  `memory` is
  // shared by the handles of up to `threads` threads (each takes its part:
  // half its table cache, half its region).
  static Status open(const std::string& dir, MemoryBudget memory, int threads,
                     std::unique_ptr<DbModel>* out);
  ~DbModel() override;

  const ModelInfo& info() const { return info_; }
  uint64_t octants() const { return octants_; }
  // The material at (x, y, z) metres in the model's frame.  NotFound when
  // the model has no octant there (a hole in an etree).
  Status lookup(double x, double y, double z, ModelHit* hit) const;
  // lookup() of n points (xyz: x, y, z of each in turn) into hits[0..n),
  // answered in Z-order so the table's pages are read once each, not once
  // a point: a batch in random order runs as fast as a sorted one.
  // REQUIRES: n < 2^32.
  Status lookup_batch(const double* xyz, size_t n, ModelHit* hits) const;

  // The error for a point outside the model's box, naming it and the box.
  Status outside_box(double x, double y, double z) const;
  std::string outside(const std::array<double, 3>& domain_m) const override;

  Material at(double x, double y, double z) const override;
  bool focus(const double lo[3], const double hi[3]) const override;
  bool loads_focus() const override { return true; }
  void vs_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                     float* out) const override;
  // at()'s materials, found as vs_on_lattice finds its points.
  void materials_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                            Material* out) const override;
  // From the focused region's Vs pyramid (model_region.h), where it holds
  // the box; false elsewhere.
  bool vs_bounds(const double lo[3], const double hi[3], float* vs_lo, float* vs_hi) const override;
  // The eight halves' pixels found once an axis (three coordinates each).
  void vs_bounds_of_eighths(const double edges[3][3], const bool want[8], float vs_lo[8],
                            float vs_hi[8], bool ok[8]) const override;
  std::string describe() const override;
  std::string geo() const override { return info_.geo; }
  bool has_q() const override { return info_.has_q; }

 private:
  struct Reader;
  DbModel() = default;
  Reader& reader() const;
  // The pixel of coordinate m (metres) on axis a, clamped into the model's
  // box.  Inline for a point well inside the box (construct asks some 15 a
  // lattice: out of line, they were a tenth of a construct from a model
  // database); pixel_near_edge answers the rest.
  uint32_t pixel_on(int a, double m, bool* clamped) const {
    const double d = m - origin_[a];
    const double t = d * inv_tick_;
    // 1 <= t < limit keeps floor_ticks in [0, limit].
    if (!(t >= 1 && t < inner_top_[a])) return pixel_near_edge(a, m, clamped);
    return static_cast<uint32_t>(floor_ticks(d, t));
  }
  uint32_t pixel_near_edge(int a, double m, bool* clamped) const;
  // floor(d / tick) from t = d / tick's product: its cast, corrected by one
  // where the product rounded across a whole number.
  int64_t floor_ticks(double d, double t) const {
    int64_t k = static_cast<int64_t>(t);
    if (double(k) * info_.tick_m > d) {
      --k;
    } else if (double(k + 1) * info_.tick_m <= d) {
      ++k;
    }
    return k;
  }
  // The pixel of (x, y, z) metres, clamped into the box (*clamped says so).
  Coord pixel_of(double x, double y, double z, bool* clamped) const;
  Status find(Reader& r, double x, double y, double z, ModelHit* hit) const;
  Status find_pixel(Reader& r, Coord t, bool clamped, double x, double y, double z,
                    ModelHit* hit) const;
  Status hole_at(double x, double y, double z) const;
  // Answers each point of the n x n x n lattice (n <= kLatticeMost; index
  // (k * n + j) * n + i): put.whole(region, lattice) where the focused
  // region holds every point, else point by point: put.in_region(region,
  // index, pixel, its cells) where the region holds it, else put(index,
  // values), values null for a hole.
  // Construct asks 5 a side of a split and 4 or 8 of a block of leaves.
  static constexpr int kLatticeMost = ModelRegion::kLatticeMost;
  template <class Put>
  void each_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                       const Put& put) const;

  std::string dir_;
  std::unique_ptr<Database> db_;
  ModelInfo info_;
  uint64_t octants_ = 0;
  uint64_t serial_ = 0;  // tells this model's readers from an earlier one's at the same address
  uint64_t pool_bytes_ = 0;
  std::unique_ptr<DecodedLeaves> decoded_;  // the readers' regions' scans keep leaves here
  size_t region_octants_ = 0;               // the most octants a reader's region holds
  uint64_t region_cells_ = 0;               // the most cells of a reader's region's raster
  std::array<uint32_t, 3> limit_{};         // ticks: the last pixel inside the box, per axis
  double inv_tick_ = 1;                     // 1 / info_.tick_m
  std::array<double, 3> origin_{};          // info_.origin_m
  std::array<double, 3> inner_top_{};       // limit_, as a double; 0 where the model is flat
  mutable std::mutex mu_;
  mutable std::unordered_map<std::thread::id, std::unique_ptr<Reader>> readers_;
};

}  // namespace weaver
