#include "modeldb/import_source.h"

#include <cmath>
#include <numeric>

namespace weaver {

int bad_model_field(const ModelValues& v, int fields) {
  for (int f = 0; f < fields; ++f) {
    if (!std::isfinite(v[f]) || (f < 3 ? v[f] <= 0 : v[f] < 0)) return f;
  }
  return -1;
}

Status bad_model_value(const std::string& what, const ModelValues& v, int f) {
  static const char* names[] = {"Vp", "Vs", "density", "Qp", "Qs"};
  return Status::Corruption(what + " has " + names[f] + " " + std::to_string(v[f]) +
                            " (velocities and density must be positive and finite)");
}

Status plan_layers(const std::string& path, LayerPlan* p, ModelInfo* info) {
  WEAVER_RETURN_IF_ERROR(read_layer_table(path, &p->table));
  const std::vector<Layer>& layers = p->table.layers;
  const double deepest = layers.back().top_m;
  if (deepest > 1e9) return Status::Corruption(path + ": a top deeper than 10^9 m");
  uint64_t gcd_mm = 0;
  for (const Layer& l : layers) gcd_mm = std::gcd(gcd_mm, uint64_t(std::llround(l.top_m * 1000)));
  // Exact where the tops' common divisor, to the millimetre, leaves at most
  // 2^19 cells down to the deepest top: a tick divides that cell.
  // Otherwise the deepest top is half the root and tops round to a tick.
  const double cell_m = gcd_mm / 1000.0;
  p->exact = gcd_mm > 0 && deepest / cell_m <= double(kRootEdge / 2);
  if (p->exact) {
    int level = 0;
    while (double(uint64_t{1} << level) < deepest / cell_m + 1) ++level;
    info->tick_m = cell_m / octant_edge(level);
  } else {
    info->tick_m = gcd_mm > 0 ? deepest / (kRootEdge / 2) : 1.0;
  }
  p->tops.clear();
  for (const Layer& l : layers) p->tops.push_back(uint32_t(std::llround(l.top_m / info->tick_m)));
  info->has_q = p->table.has_q;
  info->origin_m = {0, 0, 0};
  info->extent_m = {0, 0, kRootEdge * info->tick_m};
  char buf[120];
  std::snprintf(buf, sizeof buf, "%zu layers, tops %s to the tick (%g m)", layers.size(),
                p->exact ? "exact" : "rounded", info->tick_m);
  info->producer = buf;
  return Status::Ok();
}

// Each layer's ticks [top, next top) as the aligned power-of-two runs that
// make it up: octants at x = y = 0 (only that column is ever asked), in key
// order.  A layer thinner than a tick has none.
Status import_layers(const LayerPlan& p, uint64_t* read, const ModelEmit& emit) {
  const std::vector<Layer>& layers = p.table.layers;
  for (size_t i = 0; i < layers.size(); ++i) {
    uint64_t z = p.tops[i];
    const uint64_t end = i + 1 < layers.size() ? p.tops[i + 1] : kRootEdge;
    ++*read;
    while (z < end) {
      int level = z == 0 ? 0 : kMaxLevel - __builtin_ctzll(z);
      while (z + octant_edge(level) > end) ++level;
      const Octant o{0, 0, static_cast<uint32_t>(z), static_cast<uint8_t>(level)};
      WEAVER_RETURN_IF_ERROR(emit(o, layers[i].values));
      z += octant_edge(level);
    }
  }
  return Status::Ok();
}

}  // namespace weaver
