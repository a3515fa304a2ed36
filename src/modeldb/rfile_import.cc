#include "modeldb/rfile_import.h"

#include <algorithm>
#include <cmath>

#include "model/geo_frame.h"

namespace weaver {

Status plan_rfile(const std::string& path, MemoryBudget memory, RfilePlan* p, ModelInfo* info) {
  WEAVER_RETURN_IF_ERROR(RfileModel::open(path, memory, 1, &p->model));
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

class RfileDescent {
 public:
  RfileDescent(const RfilePlan& p, const ModelInfo& info, uint64_t* read, const ModelEmit& emit)
      : m_(*p.model), info_(info), read_(read), emit_(emit) {
    for (size_t b = 1; b < m_.header().blocks.size(); ++b) {
      const RfileBlock& k = m_.header().blocks[b];
      int level = 0;
      while (level < kMaxLevel && octant_edge(level) * info.tick_m > std::min(k.hh, k.hv)) ++level;
      levels_.push_back(level);
    }
  }

  Status visit(const Octant& o) {
    const double t = info_.tick_m, e = octant_edge(o) * t;
    const double lo[3] = {o.x * t, o.y * t, o.z * t + info_.origin_m[2]};
    const double box_hi[3] = {m_.x_extent(), m_.y_extent(), m_.z_bottom()};
    for (int a = 0; a < 3; ++a) {
      if (lo[a] >= box_hi[a]) return Status::Ok();  // wholly past the box
    }
    if (o.level < level_for(lo[2], lo[2] + e)) {
      for (int c = 0; c < 8; ++c) WEAVER_RETURN_IF_ERROR(visit(octant_child(o, c)));
      return Status::Ok();
    }
    // A cell across the box's far side samples where its centre would be,
    // held to the box (RfileModel holds points to it): no hole there.
    const double centre[3] = {lo[0] + e / 2, lo[1] + e / 2, lo[2] + e / 2};
    const Material v = m_.at(centre[0], centre[1], centre[2]);
    WEAVER_RETURN_IF_ERROR(m_.error());
    ModelValues values{};
    values[0] = v.vp, values[1] = v.vs, values[2] = v.rho, values[3] = v.qp, values[4] = v.qs;
    const int n = m_.has_q() ? 5 : 3;
    if (const int bad = bad_model_field(values, n); bad >= 0) {
      char where[96];
      std::snprintf(where, sizeof where, "%s at x %g, y %g, z %g m", m_.path().c_str(), centre[0],
                    centre[1], centre[2]);
      return bad_model_value(where, values, bad);
    }
    ++*read_;
    return emit_(o, values);
  }

 private:
  // The finest level of the blocks the depths [z0, z1) meet.
  int level_for(double z0, double z1) const {
    const auto& blocks = m_.header().blocks;
    int level = 0;
    for (size_t b = 1; b < blocks.size(); ++b) {
      const double top = b == 1 ? -HUGE_VAL : blocks[b].z0;
      const double bottom = b + 1 < blocks.size() ? blocks[b + 1].z0 : HUGE_VAL;
      if (z1 > top && z0 < bottom) level = std::max(level, levels_[b - 1]);
    }
    return level;
  }

  const RfileModel& m_;
  const ModelInfo& info_;
  uint64_t* read_;
  const ModelEmit& emit_;
  std::vector<int> levels_;  // of each material block's cells
};

}  // namespace

Status import_rfile(const RfilePlan& p, const ModelInfo& info, uint64_t* read,
                    const ModelEmit& emit) {
  RfileDescent d(p, info, read, emit);
  return d.visit(Octant{0, 0, 0, 0});
}

}  // namespace weaver
