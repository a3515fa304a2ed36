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
  // lattice_at: the values at() gives, to the bit), emitted in key order;
  // the cells wholly past the box are left out, as visit leaves them.
  Status lattice(const Octant& o, int level) {
    const int n = 1 << (level - o.level);
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
    for (int m = 0; m < n * n * n; ++m) {
      int i = 0, j = 0, k = 0;  // the m-th cell in key order
      for (int bit = 0; (1 << bit) < n; ++bit) {
        i |= ((m >> (3 * bit)) & 1) << bit;
        j |= ((m >> (3 * bit + 1)) & 1) << bit;
        k |= ((m >> (3 * bit + 2)) & 1) << bit;
      }
      if (i >= nx || j >= ny || k >= nz) continue;
      const Octant c{o.x + uint32_t(i) * step, o.y + uint32_t(j) * step, o.z + uint32_t(k) * step,
                     uint8_t(level)};
      const double centre[3] = {centres[0][i], centres[1][j], centres[2][k]};
      WEAVER_RETURN_IF_ERROR(cell(c, values_[(size_t(k) * ny + j) * nx + i], centre));
    }
    return Status::Ok();
  }

  // One cell: its values checked and emitted.
  Status cell(const Octant& o, const Material& v, const double centre[3]) {
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

  // The finest and the coarsest level of the blocks the depths [z0, z1) meet.
  void levels_for(double z0, double z1, int* finest, int* coarsest) const {
    const auto& blocks = m_.header().blocks;
    *finest = 0, *coarsest = kMaxLevel;
    for (size_t b = 1; b < blocks.size(); ++b) {
      const double top = b == 1 ? -HUGE_VAL : blocks[b].z0;
      const double bottom = b + 1 < blocks.size() ? blocks[b + 1].z0 : HUGE_VAL;
      if (z1 > top && z0 < bottom) {
        *finest = std::max(*finest, levels_[b - 1]);
        *coarsest = std::min(*coarsest, levels_[b - 1]);
      }
    }
  }

  const RfileModel& m_;
  const ModelInfo& info_;
  uint64_t* read_;
  const ModelEmit& emit_;
  std::vector<int> levels_;       // of each material block's cells
  std::vector<Material> values_;  // a lattice's
};

}  // namespace

Status import_rfile(const RfilePlan& p, const ModelInfo& info, uint64_t* read,
                    const ModelEmit& emit) {
  RfileDescent d(p, info, read, emit);
  return d.visit(Octant{0, 0, 0, 0});
}

}  // namespace weaver
