// How the descent writes its leaves: one at a time, eight siblings from one
// lattice of their centres, or a block of one level (descent.h); and the
// figures of a subtree's leaves.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include "construct/descent.h"

namespace weaver {

void SubtreeLeaves::clear() {
  keys.clear();
  payloads.clear();
  sides.clear();
  levels = {};
  elements = 0;
  blocked = 0;
  smallest_edge_m = largest_edge_m = worst_ppw = 0;
  least_vs.fill(HUGE_VAL);
  border_lo = border_hi = {};
  span = LeafSpan{};
  overflow = false;
  pieces.clear();
  added_keys.clear();
  added_payloads.clear();
  added_sides.clear();
}

uint64_t SubtreeLeaves::last_key() const {
  if (pieces.empty()) return keys.back();
  const Piece& p = pieces.back();
  return (p.added ? added_keys : keys)[p.end - 1];
}

void SubtreeLeaves::flatten(size_t bytes) {
  if (pieces.empty()) return;
  UninitVector<uint64_t> k;
  UninitVector<std::byte> b;
  std::vector<GroundSide> s;
  k.reserve(elements), b.reserve(elements * bytes);
  const bool sided = !sides.empty() || !added_sides.empty();
  for (const Piece& p : pieces) {
    const auto& from_k = p.added ? added_keys : keys;
    const auto& from_b = p.added ? added_payloads : payloads;
    k.insert(k.end(), from_k.begin() + p.begin, from_k.begin() + p.end);
    b.insert(b.end(), from_b.begin() + p.begin * bytes, from_b.begin() + p.end * bytes);
    if (sided) {
      const auto& from_s = p.added ? added_sides : sides;
      s.insert(s.end(), from_s.begin() + p.begin, from_s.begin() + p.end);
    }
  }
  keys.swap(k), payloads.swap(b), sides.swap(s);
  pieces.clear();
  added_keys.clear(), added_payloads.clear(), added_sides.clear();
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
  r->blocked += blocked;
  r->span.add(span);
}

// The edges of the finest and coarsest leaves, and the worst points per
// wavelength: for each level, its least Vs over its edge (the same value as
// the least of every leaf's own ratio, since all share the divisor).
void Descent::add_figures(SubtreeLeaves* out) const {
  bool first = true;
  for (int l = 0; l <= kMaxLevel; ++l) {
    if (out->levels[l] == 0) continue;
    const double edge_m = octant_edge(l) * p_.tick_m;
    const double ppw = out->least_vs[l] / (o_.freq * edge_m);
    if (first || edge_m < out->smallest_edge_m) out->smallest_edge_m = edge_m;
    out->largest_edge_m = std::max(out->largest_edge_m, edge_m);
    if (first || ppw < out->worst_ppw) out->worst_ppw = ppw;
    first = false;
  }
}

namespace {

// Where the leaf of Z-order t lies in a lattice of side 2^bits (x fastest):
// bit 3b of t is bit b of x, 3b + 1 of y, 3b + 2 of z.
template <int kBits>
constexpr std::array<uint16_t, 1 << (3 * kBits)> lattice_of_z_order() {
  std::array<uint16_t, 1 << (3 * kBits)> at{};
  for (int t = 0; t < (1 << (3 * kBits)); ++t) {
    int c[3] = {};
    for (int b = 0; b < kBits; ++b)
      for (int a = 0; a < 3; ++a) c[a] |= ((t >> (3 * b + a)) & 1) << b;
    at[t] = static_cast<uint16_t>((c[2] << (2 * kBits)) | (c[1] << kBits) | c[0]);
  }
  return at;
}
constexpr auto kLatticeOf4 = lattice_of_z_order<2>();
constexpr auto kLatticeOf8 = lattice_of_z_order<3>();

}  // namespace

bool Descent::emit_block(const Octant& o, int level, LeafRoom& room, SubtreeLeaves* out) const {
  const int depth = level - o.level;
  const size_t count = size_t{1} << (3 * depth);
  if (!room_for(room, out->elements + count, out)) return false;
  const size_t first = out->keys.size();
  out->keys.resize(first + count);
  out->payloads.resize((first + count) * payload_bytes_);
  const uint64_t key0 = octant_key(Octant{o.x, o.y, o.z, static_cast<uint8_t>(level)});
  const uint64_t stride = octant_key_stride(level);
  for (size_t i = 0; i < count; ++i) out->keys[first + i] = key0 + i * stride;
  // The materials a lattice of centres at a time, 8 a side where the block
  // holds that many, else 4 (the model shares each column's and each
  // depth's work); the lattices in Z-order, whose leaves follow each other.
  const int side = depth >= 3 ? 8 : 4;
  const uint16_t* lattice_of = side == 8 ? kLatticeOf8.data() : kLatticeOf4.data();
  const int per = side * side * side;
  const uint32_t e = octant_edge(level);
  alignas(Material) unsigned char storage[512 * sizeof(Material)];
  Material* m = reinterpret_cast<Material*>(storage);
  std::byte* payload = out->payloads.data() + first * payload_bytes_;
  for (size_t part = 0; part < count / per; ++part) {
    const Coord at = morton_decode(part);
    const uint32_t start[3] = {o.x + at.x * side * e, o.y + at.y * side * e, o.z + at.z * side * e};
    double centres[3][8];
    leaf_centres(start, e, side, centres);
    model_.materials_on_lattice(centres[0], centres[1], centres[2], side, m);
    for (int i = 0; i < per; ++i, payload += payload_bytes_) to_payload(m[lattice_of[i]], payload);
  }
  out->levels[level] += count;
  out->elements += count;
  out->blocked += count;
  // The block's leaves on a side of the subtree are there if it is.
  note_border(o, e, out);
  return true;
}

// The materials at the centres of o's eight children (child c's in m[c]),
// from one lattice, computed as material() computes each.
void Descent::child_materials(const Octant& o, Material* m) const {
  const uint32_t start[3] = {o.x, o.y, o.z};
  double centres[3][8];
  leaf_centres(start, octant_edge(o.level + 1), 2, centres);
  model_.materials_on_lattice(centres[0], centres[1], centres[2], 2, m);
}

void Descent::children_materials(const Octant& o, std::byte* out) const {
  alignas(Material) unsigned char storage[8 * sizeof(Material)];
  Material* m = reinterpret_cast<Material*>(storage);
  child_materials(o, m);
  for (int c = 0; c < 8; ++c) to_payload(m[c], out + c * payload_bytes_);
}

// o's eight children, all leaves, with their materials from one lattice of
// their centres.
bool Descent::emit_siblings(const Octant& o, const Judgement* children, LeafRoom& room,
                            SubtreeLeaves* out) const {
  if (!room_for(room, out->elements + 8, out)) return false;
  // Storage the model fills (every model assigns each Material whole), not
  // eight Materials zeroed first: that zeroing was a `rep stos`, a fifth of
  // this function.  (An array of bytes implicitly creates the Materials.)
  alignas(Material) unsigned char storage[8 * sizeof(Material)];
  Material* m = reinterpret_cast<Material*>(storage);
  child_materials(o, m);
  // The children's keys from their parent's (one Morton encoding, not
  // eight); the subtree's borders only where the parent touches one.
  const uint64_t parent = octant_key(o);
  const bool at_border = touches_border(o, out->root);
  out->payloads.resize(out->payloads.size() + 8 * payload_bytes_);
  for (int c = 0; c < 8; ++c) {
    emit(octant_child(o, c), octant_key_child(parent, c), children[c], m[c], at_border, out);
  }
  return true;
}

// As weaver balance computes a new leaf's centre: its tables are the same.
Material Descent::material_at_centre(const Octant& o) const {
  const double t = p_.tick_m, half = octant_edge(o) * t / 2;
  return model_.at(o.x * t + half, o.y * t + half, o.z * t + half);
}

void Descent::material(const Octant& o, std::byte* out) const {
  to_payload(material_at_centre(o), out);
}

bool Descent::touches_border(const Octant& o, const Octant& root) {
  const uint32_t e = octant_edge(o), root_e = octant_edge(root);
  const uint32_t c[3] = {o.x, o.y, o.z}, r[3] = {root.x, root.y, root.z};
  bool touches = false;
  for (int a = 0; a < 3; ++a) touches |= (c[a] == r[a]) | (c[a] + e == r[a] + root_e);
  return touches;
}

// The worst points per wavelength are those of the least sample; a leaf
// settled by bounds is sampled only if its floor is below the least Vs of
// its level so far (else it cannot be the worst).
void Descent::emit(const Octant& o, uint64_t key, const Judgement& j, const Material& m,
                   bool at_border, SubtreeLeaves* out) const {
  double& least = out->least_vs[o.level];
  if (j.vs >= 0) {
    least = std::min(least, j.vs);
  } else if (j.floor < least) {
    float samples[27];
    lattice(o, 3, samples);
    least = std::min(least, vs_min_of(samples));
  }
  if (p_.carved) out->sides.push_back(j.side);
  to_payload(m, out->payloads.data() + out->keys.size() * payload_bytes_);
  out->keys.push_back(key);
  ++out->levels[o.level];
  ++out->elements;
  // How far the subtree's balance looks out (subtree_balance.h) follows the
  // elements alone: a chain of splits that ends in one starts within its
  // own edge of it, whatever air it crosses, and air's own refinement is
  // cut away with it.
  if (j.side == GroundSide::kAir || !at_border) return;
  note_border(o, octant_edge(o), out);
}

// Leaves of edge e fill o: on each side of the subtree (out->root) that o
// touches, the largest leaf there is at least e.
void Descent::note_border(const Octant& o, uint32_t e, SubtreeLeaves* out) {
  const uint32_t o_e = octant_edge(o), root_e = octant_edge(out->root);
  const uint32_t c[3] = {o.x, o.y, o.z}, r[3] = {out->root.x, out->root.y, out->root.z};
  for (int a = 0; a < 3; ++a) {
    if (c[a] == r[a]) out->border_lo[a] = std::max(out->border_lo[a], e);
    if (c[a] + o_e == r[a] + root_e) out->border_hi[a] = std::max(out->border_hi[a], e);
  }
}

}  // namespace weaver
