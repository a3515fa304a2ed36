#include "modeldb/rfile_import.h"

#include <algorithm>
#include <cmath>

#include "model/block_merge.h"
#include "model/geo_frame.h"
#include "util/ordered_run.h"

namespace weaver {

namespace {

// The import's column cache a thread, at most: its subtrees come in key
// order and read each column about once, so a cache the size of the core's
// own does (measured on the 1.09 GB test rfile, --memory 1G, 2 threads:
// 2.63 s at 8 MB a thread against 2.97 s at the 128 MB --memory gave it,
// whose slots are written cold; 4.4 against 5.1 s of CPU).
constexpr uint64_t kImportCacheBytes = 8ull << 20;

}  // namespace

Status plan_rfile(const std::string& path, MemoryBudget memory, int threads, RfilePlan* p,
                  ModelInfo* info) {
  threads = std::max(1, threads);
  const MemoryBudget cache(std::min(memory.bytes(), kImportCacheBytes * uint64_t(threads)));
  WEAVER_RETURN_IF_ERROR(RfileModel::open(path, cache, threads, &p->model));
  const RfileModel& m = *p->model;
  const double extent[3] = {m.x_extent(), m.y_extent(), m.z_bottom() - m.z_top()};
  p->root_m = std::max({extent[0], extent[1], extent[2]});
  info->tick_m = p->root_m / kRootEdge;
  info->origin_m = {0, 0, m.z_top()};
  info->extent_m = {extent[0], extent[1], extent[2]};
  info->has_q = m.has_q();
  info->geo = m.geo();
  info->producer = "SW4 rfile, " + std::to_string(m.header().blocks.size() - 1) +
                   " material blocks; PROJ " + m.header().proj;
  std::replace(info->producer.begin(), info->producer.end(), ';', ' ');
  return Status::Ok();
}

namespace {

// The level of each material block's cells: its smaller spacing rounded
// down to a power of two of the tick.
std::vector<int> block_levels(const RfileModel& m, double tick_m) {
  std::vector<int> levels;
  for (size_t b = 1; b < m.header().blocks.size(); ++b) {
    const RfileBlock& k = m.header().blocks[b];
    int level = 0;
    while (level < kMaxLevel && octant_edge(level) * tick_m > std::min(k.hh, k.hv)) ++level;
    levels.push_back(level);
  }
  return levels;
}

class RfileDescent {
 public:
  RfileDescent(const RfilePlan& p, const ModelInfo& info, uint64_t* read, MaterialMerger* out)
      : m_(*p.model), info_(info), read_(read), out_(out), levels_(block_levels(m_, info.tick_m)) {}

  Status visit(const Octant& o) {
    const double t = info_.tick_m, e = octant_edge(o) * t;
    const double lo[3] = {o.x * t, o.y * t, o.z * t + info_.origin_m[2]};
    const double box_hi[3] = {m_.x_extent(), m_.y_extent(), m_.z_bottom()};
    for (int a = 0; a < 3; ++a) {
      if (lo[a] >= box_hi[a]) return Status::Ok();  // wholly past the box
    }
    int finest = 0, coarsest = 0;
    levels_for(lo[2], lo[2] + e, &finest, &coarsest);
    if (o.level < finest) {
      // Cells of one size through the whole octant, and few enough: a
      // lattice, its columns read once.
      if (coarsest == finest && finest - o.level <= kLatticeLevels) return lattice(o, finest);
      for (int c = 0; c < 8; ++c) WEAVER_RETURN_IF_ERROR(visit(octant_child(o, c)));
      return Status::Ok();
    }
    // A cell across the box's far side samples where its centre would be,
    // held to the box (RfileModel holds points to it): no hole there.
    const double centre[3] = {lo[0] + e / 2, lo[1] + e / 2, lo[2] + e / 2};
    WEAVER_RETURN_IF_ERROR(cell(o, m_.at(centre[0], centre[1], centre[2]), centre));
    return Status::Ok();
  }

 private:
  // Octants of up to 2^kLatticeLevels cells a side are sampled as a lattice.
  static constexpr int kLatticeLevels = 4;

  // The cells of level `level` in o, sampled at once (RfileModel::
  // lattice_at: the values at() gives, to the bit), merged in memory
  // (block_merge.h: what the merger would make of them one by one) and
  // passed on in key order; the cells wholly past the box are left out, as
  // visit leaves them.
  Status lattice(const Octant& o, int level) {
    const int levels = level - o.level, n = 1 << levels;
    const uint32_t step = octant_edge(level);
    const double t = info_.tick_m, e = step * t;
    const double box_hi[3] = {m_.x_extent(), m_.y_extent(), m_.z_bottom()};
    const uint32_t corner[3] = {o.x, o.y, o.z};
    std::vector<double> centres[3];
    for (int a = 0; a < 3; ++a) {
      for (int i = 0; i < n; ++i) {
        const double lo = (corner[a] + i * step) * t + (a == 2 ? info_.origin_m[2] : 0.0);
        if (lo >= box_hi[a]) break;
        centres[a].push_back(lo + e / 2);
      }
    }
    const int nx = int(centres[0].size()), ny = int(centres[1].size()), nz = int(centres[2].size());
    values_.resize(size_t(nx) * ny * nz);
    m_.lattice_at(centres[0].data(), nx, centres[1].data(), ny, centres[2].data(), nz,
                  values_.data());
    WEAVER_RETURN_IF_ERROR(m_.error());
    BlockMerger& block = block_merger(levels);
    std::vector<ModelValues>& values = block.values();
    std::vector<uint8_t>& present = block.present();
    const int fields = m_.has_q() ? 5 : 3;
    for (int m = 0; m < n * n * n; ++m) {
      int i = 0, j = 0, k = 0;  // the m-th cell in key order
      for (int bit = 0; bit < levels; ++bit) {
        i |= ((m >> (3 * bit)) & 1) << bit;
        j |= ((m >> (3 * bit + 1)) & 1) << bit;
        k |= ((m >> (3 * bit + 2)) & 1) << bit;
      }
      present[m] = i < nx && j < ny && k < nz;
      if (!present[m]) continue;
      const Material& v = values_[(size_t(k) * ny + j) * nx + i];
      values[m] = ModelValues{v.vp, v.vs, v.rho, v.qp, v.qs};
      if (!model_fields_ok(values[m], fields)) {
        const double centre[3] = {centres[0][i], centres[1][j], centres[2][k]};
        return bad_value(values[m], bad_model_field(values[m], fields), centre);
      }
      ++*read_;
    }
    return block.merge_into(o, *out_);
  }

  // The in-memory merger of lattices `levels` levels deep, made on first use.
  BlockMerger& block_merger(int levels) {
    std::unique_ptr<BlockMerger>& b = blocks_[levels - 1];
    if (!b) b = std::make_unique<BlockMerger>(levels);
    return *b;
  }

  Status bad_value(const ModelValues& values, int bad, const double centre[3]) const {
    char where[96];
    std::snprintf(where, sizeof where, "%s at x %g, y %g, z %g m", m_.path().c_str(), centre[0],
                  centre[1], centre[2]);
    return bad_model_value(where, values, bad);
  }

  // One cell: its values checked and emitted.
  Status cell(const Octant& o, const Material& v, const double centre[3]) {
    WEAVER_RETURN_IF_ERROR(m_.error());
    ModelValues values{};
    values[0] = v.vp, values[1] = v.vs, values[2] = v.rho, values[3] = v.qp, values[4] = v.qs;
    const int n = m_.has_q() ? 5 : 3;
    if (!model_fields_ok(values, n)) return bad_value(values, bad_model_field(values, n), centre);
    ++*read_;
    return out_->add(o, values);
  }

  // The finest and the coarsest level of the blocks the depths [z0, z1) meet.
  void levels_for(double z0, double z1, int* finest, int* coarsest) const {
    const auto& blocks = m_.header().blocks;
    *finest = 0, *coarsest = kMaxLevel;
    for (size_t b = 1; b < blocks.size(); ++b) {
      double top, bottom;
      rfile_block_depths(m_.header(), b, &top, &bottom);
      if (z1 > top && z0 < bottom) {
        *finest = std::max(*finest, levels_[b - 1]);
        *coarsest = std::min(*coarsest, levels_[b - 1]);
      }
    }
  }

  const RfileModel& m_;
  const ModelInfo& info_;
  uint64_t* read_;
  MaterialMerger* out_;
  std::vector<int> levels_;       // of each material block's cells
  std::vector<Material> values_;  // a lattice's
  std::unique_ptr<BlockMerger> blocks_[kLatticeLevels];
};

// The subtrees the import is cut into, in key order: an octant is split
// while its cells (counted from the blocks' cell sizes over the part of it
// inside the box) are more than the cap and its children are no finer
// than the finest cells it holds.
class RfileTasks {
 public:
  RfileTasks(const RfileModel& m, const ModelInfo& info, uint64_t cap)
      : m_(m), info_(info), cap_(cap), levels_(block_levels(m, info.tick_m)) {
    stack_.push_back(Octant{0, 0, 0, 0});
  }
  bool next(Octant* out) {
    while (!stack_.empty()) {
      const Octant o = stack_.back();
      stack_.pop_back();
      int finest = 0;
      const double cells = count(o, &finest);
      if (cells == 0) continue;  // wholly past the box
      if (cells <= double(cap_) || o.level >= finest) {
        *out = o;
        return true;
      }
      for (int c = 7; c >= 0; --c) stack_.push_back(octant_child(o, c));
    }
    return false;
  }

 private:
  // The cells of o inside the box, and the level of the finest of them.
  double count(const Octant& o, int* finest) const {
    const double t = info_.tick_m, e = octant_edge(o) * t;
    const double lo[3] = {o.x * t, o.y * t, o.z * t + info_.origin_m[2]};
    const double hi[3] = {std::min(lo[0] + e, m_.x_extent()), std::min(lo[1] + e, m_.y_extent()),
                          std::min(lo[2] + e, m_.z_bottom())};
    if (hi[0] <= lo[0] || hi[1] <= lo[1] || hi[2] <= lo[2]) return 0;
    const auto& blocks = m_.header().blocks;
    double cells = 0;
    for (size_t b = 1; b < blocks.size(); ++b) {
      double top, bottom;
      rfile_block_depths(m_.header(), b, &top, &bottom);
      const double z = std::min(hi[2], bottom) - std::max(lo[2], top);
      if (z <= 0) continue;
      const double c = octant_edge(levels_[b - 1]) * t;
      cells += std::ceil((hi[0] - lo[0]) / c) * std::ceil((hi[1] - lo[1]) / c) * std::ceil(z / c);
      *finest = std::max(*finest, levels_[b - 1]);
    }
    return cells;
  }

  const RfileModel& m_;
  const ModelInfo& info_;
  uint64_t cap_;
  std::vector<int> levels_;
  std::vector<Octant> stack_;  // the next on top
};

// One subtree's cells, sampled and merged by a worker, passed on in turn.
struct RfileTask {
  Octant root;
  std::vector<MaterialMerger::Entry> merged;
  uint64_t read = 0;
  Status status;
};

}  // namespace

Status import_rfile(const RfilePlan& p, const ModelInfo& info, const RfileImportRun& run,
                    uint64_t* read, MaterialMerger* out) {
  const int threads = std::max(1, run.threads);
  if (threads == 1) {
    RfileDescent d(p, info, read, out);
    return d.visit(Octant{0, 0, 0, 0});
  }
  RfileTasks tasks(*p.model, info, std::max<uint64_t>(1, run.task_cells));
  Status st;
  const auto make = [&](RfileTask* t) {
    t->merged.clear(), t->read = 0, t->status = Status::Ok();
    return tasks.next(&t->root);
  };
  // A subtree's records merge alone as they would in the whole stream (its
  // records are a run of it); the merger after takes its entries on.
  const auto work = [&](int, RfileTask* t) {
    MaterialMerger local(run.tolerance, run.fields, [t](const MaterialMerger::Entry& e) {
      t->merged.push_back(e);
      return Status::Ok();
    });
    RfileDescent d(p, info, &t->read, &local);
    t->status = d.visit(t->root);
    if (t->status.ok()) t->status = local.finish();
  };
  const auto write = [&](RfileTask* t) {
    st = t->status;
    for (size_t i = 0; st.ok() && i < t->merged.size(); ++i) st = out->add(t->merged[i]);
    *read += t->read;
    return st.ok();
  };
  // Two subtrees a thread: one sampled while the other waits its turn.
  OrderedRun<RfileTask> ordered(size_t(2 * threads), make, work, write);
  ordered.go(threads);
  return st;
}

}  // namespace weaver
