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

// Point i of an n-point lattice axis (n = 3 or 5) over an octant starting
// at tick a with edge e sits at a + i e / (n - 1) ticks: a whole number of
// quarter ticks, so every octant that shares the point computes the same
// coordinate, rounded once.
void Descent::lattice(const Octant& o, int n, float* out) const {
  const double quarter = p_.tick_m / 4;
  const uint64_t step = 4 * uint64_t{octant_edge(o)} / (n - 1);
  double axes[3][5];
  const uint32_t start[3] = {o.x, o.y, o.z};
  for (int a = 0; a < 3; ++a)
    for (int i = 0; i < n; ++i) axes[a][i] = double(4 * uint64_t{start[a]} + i * step) * quarter;
  model_.vs_on_lattice(axes[0], axes[1], axes[2], n, out);
}

// The least Vs over the 27 sample points, floored by --vs-min.
// Four running minima, not std::min_element's one: 27 dependent compares
// were a fifth of construct.  (The minimum is the same in any order.)
double Descent::vs_min_of(const float* samples) const {
  float m[4] = {samples[0], samples[1], samples[2], samples[3]};
  for (int i = 4; i < 24; i += 4) {
    for (int k = 0; k < 4; ++k) m[k] = std::min(m[k], samples[i + k]);
  }
  for (int i = 24; i < 27; ++i) m[0] = std::min(m[0], samples[i]);
  return std::max<double>(std::min(std::min(m[0], m[1]), std::min(m[2], m[3])), o_.vs_min);
}

bool Descent::splits(const Octant& o, double vs) const {
  const double edge_m = octant_edge(o) * p_.tick_m;
  const bool too_big = edge_m > vs * inv_rate_;
  return o.level < o_.min_level || (too_big && o.level < o_.max_level);
}

bool Descent::splits(const Octant& o) const {
  float samples[27];
  lattice(o, 3, samples);
  return splits(o, vs_min_of(samples));
}

void Descent::visit_subtree(const Octant& o, size_t cap, SubtreeLeaves* out) const {
  out->clear();
  // The subtree's closed box, as lattice() computes its far corner.
  const double quarter = p_.tick_m / 4;
  const uint64_t e4 = 4 * uint64_t{octant_edge(o)};
  const double lo[3] = {double(4 * uint64_t{o.x}) * quarter, double(4 * uint64_t{o.y}) * quarter,
                        double(4 * uint64_t{o.z}) * quarter};
  const double hi[3] = {double(4 * uint64_t{o.x} + e4) * quarter,
                        double(4 * uint64_t{o.y} + e4) * quarter,
                        double(4 * uint64_t{o.z} + e4) * quarter};
  model_.focus(lo, hi);
  float samples[27];
  lattice(o, 3, samples);
  out->overflow = !visit(o, samples, cap, out);
}

// o's 27 samples are given (its parent's lattice held them).  A split
// evaluates its 5 x 5 x 5 lattice once, 125 samples for the 216 of the
// children's own lattices, and hands each child its 27.  False once the
// subtree has more than cap leaves.
bool Descent::visit(const Octant& o, const float* samples, size_t cap, SubtreeLeaves* out) const {
  const double vs = vs_min_of(samples);
  if (splits(o, vs)) {
    float children[8][27];
    children_samples(o, children);
    for (int c = 0; c < 8; ++c) {
      if (!visit(octant_child(o, c), children[c], cap, out)) return false;
    }
    return true;
  }
  if (out->elements == cap) return false;
  emit(o, octant_edge(o) * p_.tick_m, vs, out);
  return true;
}

void Descent::children_samples(const Octant& o, float (*out)[27]) const {
  float fine[125];
  lattice(o, 5, fine);
  for (int c = 0; c < 8; ++c) {
    const int cx = 2 * (c & 1), cy = (c & 2), cz = (c & 4) / 2;
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i)
          out[c][(k * 3 + j) * 3 + i] = fine[((cz + k) * 5 + cy + j) * 5 + cx + i];
  }
}

void Descent::material(const Octant& o, std::byte* out) const {
  // As weaver balance computes a new leaf's centre: its tables are the same.
  const double t = p_.tick_m, half = octant_edge(o) * t / 2;
  const Material m = model_.at(o.x * t + half, o.y * t + half, o.z * t + half);
  const float f[5] = {m.vp, m.vs, m.rho, m.qp, m.qs};
  static_assert(sizeof f == kMaxPayloadBytes);
  std::memcpy(out, f, payload_bytes());
}

void Descent::emit(const Octant& o, double edge_m, double vs, SubtreeLeaves* out) const {
  out->keys.push_back(octant_key(o));
  const size_t at = out->payloads.size();
  out->payloads.resize(at + payload_bytes());
  material(o, out->payloads.data() + at);
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
