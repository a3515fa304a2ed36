#include "construct/descent.h"

#include <algorithm>
#include <cstring>

namespace weaver {

void SubtreeLeaves::clear() {
  keys.clear();
  payloads.clear();
  levels = {};
  elements = 0;
  smallest_edge_m = largest_edge_m = worst_ppw = 0;
  overflow = false;
}

void SubtreeLeaves::add_to(ConstructResult* r) const {
  if (elements == 0) return;
  for (size_t l = 0; l < levels.size(); ++l) r->levels[l] += levels[l];
  if (r->elements == 0 || smallest_edge_m < r->smallest_edge_m) {
    r->smallest_edge_m = smallest_edge_m;
  }
  r->largest_edge_m = std::max(r->largest_edge_m, largest_edge_m);
  if (r->elements == 0 || worst_ppw < r->worst_ppw) r->worst_ppw = worst_ppw;
  r->elements += elements;
}

// The least Vs over the 27 sample points, floored by --vs-min.
double Descent::vs_min_of(const Octant& o) const {
  const double t = p_.tick_m, h = octant_edge(o) * t / 2;
  return std::max(model_.min_vs_on_lattice(o.x * t, o.y * t, o.z * t, h), o_.vs_min);
}

bool Descent::splits(const Octant& o) const {
  const double edge_m = octant_edge(o) * p_.tick_m;
  const bool too_big = edge_m > vs_min_of(o) * inv_rate_;
  return o.level < o_.min_level || (too_big && o.level < o_.max_level);
}

void Descent::visit_subtree(const Octant& o, size_t cap, SubtreeLeaves* out) const {
  out->clear();
  out->overflow = !visit(o, cap, out);
}

// False once the subtree has more than cap leaves.
bool Descent::visit(const Octant& o, size_t cap, SubtreeLeaves* out) const {
  const double edge_m = octant_edge(o) * p_.tick_m;
  const double vs = vs_min_of(o);
  const bool too_big = edge_m > vs * inv_rate_;
  if (o.level < o_.min_level || (too_big && o.level < o_.max_level)) {
    for (int c = 0; c < 8; ++c) {
      if (!visit(octant_child(o, c), cap, out)) return false;
    }
    return true;
  }
  if (out->elements == cap) return false;
  emit(o, edge_m, vs, out);
  return true;
}

void Descent::emit(const Octant& o, double edge_m, double vs, SubtreeLeaves* out) const {
  const double t = p_.tick_m, half = edge_m / 2;
  const Material m = model_.at(o.x * t + half, o.y * t + half, o.z * t + half);
  out->keys.push_back(octant_key(o));
  const float f[3] = {m.vp, m.vs, m.rho};
  static_assert(sizeof f == kPayloadBytes);
  const size_t at = out->payloads.size();
  out->payloads.resize(at + sizeof f);
  std::memcpy(out->payloads.data() + at, f, sizeof f);
  ++out->levels[o.level];
  const double ppw = vs / (o_.freq * edge_m);
  if (out->elements == 0 || edge_m < out->smallest_edge_m) out->smallest_edge_m = edge_m;
  out->largest_edge_m = std::max(out->largest_edge_m, edge_m);
  if (out->elements == 0 || ppw < out->worst_ppw) out->worst_ppw = ppw;
  ++out->elements;
}

SubtreeList::SubtreeList(const Descent& d, const ConstructPlan& p, int task_level)
    : descent_(d), task_level_(task_level) {
  const uint32_t e = octant_edge(p.block_level);
  for (uint32_t k = 0; k < p.blocks[2]; ++k)
    for (uint32_t j = 0; j < p.blocks[1]; ++j)
      for (uint32_t i = 0; i < p.blocks[0]; ++i) {
        stack_.push_back({i * e, j * e, k * e, uint8_t(p.block_level)});
      }
  // Z-order, the first on top.
  std::sort(stack_.begin(), stack_.end(),
            [](const Octant& a, const Octant& b) { return octant_key(a) > octant_key(b); });
}

bool SubtreeList::next(Octant* o) {
  while (!stack_.empty()) {
    const Octant top = stack_.back();
    stack_.pop_back();
    if (top.level >= task_level_ || !descent_.splits(top)) {
      *o = top;
      return true;
    }
    for (int c = 7; c >= 0; --c) stack_.push_back(octant_child(top, c));
  }
  return false;
}

}  // namespace weaver
