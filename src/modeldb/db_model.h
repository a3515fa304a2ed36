// A velocity model read from a model database (modeldb/model_table.h): the
// material at a point is the model octant holding it, found by the
// aggregate-hit (floor) query.  Points outside the model's box are clamped
// into it.  Safe to use from many threads at once (construct's workers):
// each thread gets its own table handle, with its own share of the cache,
// and remembers the last octant it hit.
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "model/material_merge.h"
#include "model/velocity_model.h"
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
  // Opens the model table of the database in dir, read-only.  Each thread's
  // handle takes a quarter of `memory` (construct runs at most a few).
  static Status open(const std::string& dir, MemoryBudget memory, std::unique_ptr<DbModel>* out);
  ~DbModel() override;

  const ModelInfo& info() const { return info_; }
  uint64_t octants() const { return octants_; }
  // The material at (x, y, z) metres in the model's frame.  NotFound when
  // the model has no octant there (a hole in an etree).
  Status lookup(double x, double y, double z, ModelHit* hit) const;

  Material at(double x, double y, double z) const override;
  void vs_on_lattice(const double* xs, const double* ys, const double* zs, int n,
                     float* out) const override;
  std::string describe() const override;

 private:
  struct Reader;
  DbModel() = default;
  Reader& reader() const;
  Status find(Reader& r, double x, double y, double z, ModelHit* hit) const;

  std::string dir_;
  std::unique_ptr<Database> db_;
  ModelInfo info_;
  uint64_t octants_ = 0;
  uint64_t pool_bytes_ = 0;
  std::array<uint32_t, 3> limit_{};  // ticks: the last pixel inside the box, per axis
  mutable std::mutex mu_;
  mutable std::unordered_map<std::thread::id, std::unique_ptr<Reader>> readers_;
};

}  // namespace weaver
