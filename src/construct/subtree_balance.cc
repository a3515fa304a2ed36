#include "construct/subtree_balance.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>

#include "util/parent_asks.h"
#include "util/resolve_split.h"

namespace weaver {
namespace {

// Whether octant x meets the half-open box [lo, hi) with some volume.
bool meets(const Octant& x, const int64_t lo[3], const int64_t hi[3]) {
  const int64_t e = octant_edge(x);
  const int64_t c[3] = {x.x, x.y, x.z};
  for (int a = 0; a < 3; ++a) {
    if (c[a] >= hi[a] || c[a] + e <= lo[a]) return false;
  }
  return true;
}

// By child position: the face and edge directions (a bit each, as in
// kFaceAndEdgeDirections) whose neighbour lies outside the parent.
constexpr std::array<uint32_t, 8> leaving_parent_table() {
  std::array<uint32_t, 8> t{};
  for (int c = 0; c < 8; ++c) {
    for (size_t i = 0; i < kFaceAndEdgeDirections.size(); ++i) {
      const Direction d = kFaceAndEdgeDirections[i];
      const int step[3] = {d.dx, d.dy, d.dz};
      for (int a = 0; a < 3; ++a) {
        const bool far = (c >> a) & 1;
        if ((step[a] > 0 && far) || (step[a] < 0 && !far)) t[c] |= 1u << i;
      }
    }
  }
  return t;
}
constexpr std::array<uint32_t, 8> kLeavingParent = leaving_parent_table();

bool inside(const Octant& x, const Octant& root) {
  return x.level >= root.level && octant_ancestor(x, root.level) == root;
}

}  // namespace

SubtreeBalancer::SubtreeBalancer(const Descent& descent, bool fill_material)
    : descent_(descent), fill_(fill_material) {}

void SubtreeBalancer::balance(const Octant& root, SubtreeLeaves* leaves) {
  if (leaves->keys.empty()) return;
  grow_box(root, *leaves);
  const ConstructPlan& p = descent_.plan();
  // The blocks the grown box meets, each descended again where it meets it.
  const int64_t block = octant_edge(p.block_level);
  int64_t first[3], last[3];
  for (int a = 0; a < 3; ++a) {
    first[a] = std::max<int64_t>(0, box_lo_[a] / block);
    last[a] = std::min<int64_t>(p.blocks[a], (box_hi_[a] + block - 1) / block);
  }
  const double lo_m[3] = {box_lo_[0] * p.tick_m, box_lo_[1] * p.tick_m, box_lo_[2] * p.tick_m};
  const double hi_m[3] = {box_hi_[0] * p.tick_m, box_hi_[1] * p.tick_m, box_hi_[2] * p.tick_m};
  descent_.model().focus(lo_m, hi_m);
  blocks_.clear();
  for (int64_t k = first[2]; k < last[2]; ++k)
    for (int64_t j = first[1]; j < last[1]; ++j)
      for (int64_t i = first[0]; i < last[0]; ++i) {
        blocks_.push_back({uint32_t(i * block), uint32_t(j * block), uint32_t(k * block),
                           uint8_t(p.block_level)});
      }
  std::sort(blocks_.begin(), blocks_.end(),
            [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
  collected_.clear();
  for (const Octant& b : blocks_) {
    if (wanted(b, root)) collect(b, nullptr, root);
  }
  collected_count_ += collected_.size();
  local_.resize(collected_.size() + leaves->keys.size());
  std::merge(collected_.begin(), collected_.end(), leaves->keys.begin(), leaves->keys.end(),
             local_.begin());
  ripple();
  // Nothing created inside the subtree (most subtrees): its leaves stand.
  const auto inside_root = std::lower_bound(created_.begin(), created_.end(), octant_key(root));
  if (inside_root == created_.end() || *inside_root >= octant_key_subtree_end(root)) return;
  refine(root, leaves);
}

// The subtree's box grown on each side by the edge of the largest own leaf
// touching that side, within the domain.
void SubtreeBalancer::grow_box(const Octant& root, const SubtreeLeaves& leaves) {
  const int64_t r_lo[3] = {root.x, root.y, root.z};
  const int64_t r_edge = octant_edge(root);
  int64_t grow_lo[3] = {0, 0, 0}, grow_hi[3] = {0, 0, 0};
  for (uint64_t key : leaves.keys) {
    const Octant o = octant_from_key(key);
    const int64_t e = octant_edge(o), c[3] = {o.x, o.y, o.z};
    for (int a = 0; a < 3; ++a) {
      if (c[a] == r_lo[a]) grow_lo[a] = std::max(grow_lo[a], e);
      if (c[a] + e == r_lo[a] + r_edge) grow_hi[a] = std::max(grow_hi[a], e);
    }
  }
  const ConstructPlan& p = descent_.plan();
  for (int a = 0; a < 3; ++a) {
    const int64_t domain_end = int64_t{p.blocks[a]} * octant_edge(p.block_level);
    box_lo_[a] = std::max<int64_t>(0, r_lo[a] - grow_lo[a]);
    box_hi_[a] = std::min<int64_t>(domain_end, r_lo[a] + r_edge + grow_hi[a]);
  }
}

bool SubtreeBalancer::wanted(const Octant& x, const Octant& root) const {
  return meets(x, box_lo_, box_hi_) && !inside(x, root);
}

// The input leaves under x that meet the grown box, outside root, into
// collected_ in key order.  x's ancestors split (it is a block or a child
// of a split); samples are its 27 (or null: x samples them itself).  A
// split hands its children their samples from its 5 x 5 x 5 lattice when
// most of them are wanted (125 points for 8 x 27), else each takes its own.
void SubtreeBalancer::collect(const Octant& x, const float* samples, const Octant& root) {
  bool split = inside(root, x);  // an ancestor of root splits: root is a subtree of the descent
  if (!split) {
    float own[27];
    if (samples == nullptr) descent_.sample_points(x, own), samples = own;
    split = descent_.splits_sampled(x, samples);
  }
  if (!split) {
    collected_.push_back(octant_key(x));
    return;
  }
  bool want[8];
  int wanted_children = 0;
  for (int c = 0; c < 8; ++c) wanted_children += want[c] = wanted(octant_child(x, c), root);
  float children[8][27];
  const bool shared = wanted_children >= 5;
  if (shared) descent_.children_samples(x, children);
  for (int c = 0; c < 8; ++c) {
    if (want[c]) collect(octant_child(x, c), shared ? children[c] : nullptr, root);
  }
}

// The created octants (strictly inside a local leaf, required by the
// balance), into created_ in key order.
//
// A leaf of level l asks for octants of level l - 1, which lie strictly
// inside a leaf only if that leaf's level is l - 2 or coarser.  So only the
// leaves two levels finer than the coarsest ask (a subtree graded by one
// level at most has nothing to do), and only the leaves two levels coarser
// than the finest go into the map as leaves: the others are found resolved
// all the same, since their parents are inner.
void SubtreeBalancer::ripple() {
  created_.clear();
  LevelCounts count{};
  for (uint64_t key : local_) ++count[octant_key_level(key)];
  int coarsest = 0, finest = kMaxLevel;
  while (count[coarsest] == 0) ++coarsest;
  while (count[finest] == 0) --finest;
  if (finest - coarsest < 2) return;
  map_.reset(local_.size() / 4 + 64);
  uint64_t last_parent = ~uint64_t{0};
  for (uint64_t key : local_) {
    const int level = octant_key_level(key);
    if (level <= finest - 2) map_.add(key, OctantMap::kLeaf);
    if (level == 0) continue;
    const uint64_t parent = octant_key_parent(key);
    if (level >= coarsest + 2) add_ask(level, parent, 1u << octant_key_child_id(key));
    if (parent == last_parent) continue;
    last_parent = parent;
    for (uint64_t q = parent; map_.add(q, OctantMap::kInner) && octant_key_level(q) > 0;) {
      q = octant_key_parent(q);
    }
  }
  for (int l = finest; l >= 1; --l) ask_level(l);
  std::sort(created_.begin(), created_.end());
}

// A leaf's ask, merged with its siblings' (they come one after another
// among the leaves of their level).
void SubtreeBalancer::add_ask(int level, uint64_t parent, unsigned child_bit) {
  std::vector<Ask>& asks = asks_[level];
  if (!asks.empty() && asks.back().parent == parent) {
    asks.back().children |= child_bit;
  } else {
    asks.push_back({parent, child_bit, false});
  }
}

// The asks of level l's parents: each neighbour one level coarser that is
// strictly inside a leaf (its nearest octant in the map, going up, is a
// leaf or created) is created, and its parent asks in turn at level l - 1.
// A neighbour whose nearest octant is inner lies where no local leaf is.
void SubtreeBalancer::ask_level(int l) {
  std::vector<Ask>& asks = asks_[l];
  if (unsorted_[l]) {
    std::sort(asks.begin(), asks.end(),
              [](const Ask& a, const Ask& b) { return a.parent < b.parent; });
    size_t n = 0;
    for (const Ask& a : asks) {
      if (n > 0 && asks[n - 1].parent == a.parent) {
        asks[n - 1].children |= a.children;
        asks[n - 1].created |= a.created;
      } else {
        asks[n++] = a;
      }
    }
    asks.resize(n);
    unsorted_[l] = false;
  }
  for (const Ask& a : asks) {
    uint32_t asked = parent_asks::kTouchedBy[a.children];
    // The parent's siblings are there (leaves or inner) when its own parent
    // is inner, as it is above a leaf of the input: only the neighbours
    // outside it are asked about.
    if (!a.created && l >= 2) asked &= kLeavingParent[octant_key_child_id(a.parent)];
    for (uint32_t bits = asked; bits != 0; bits &= bits - 1) {
      uint64_t nb = 0;
      if (!octant_key_neighbour(a.parent, kFaceAndEdgeDirections[std::countr_zero(bits)], &nb)) {
        continue;
      }
      if (map_.find(nb) != OctantMap::kAbsent) continue;  // resolved, or created already
      OctantMap::Kind above = OctantMap::kAbsent;
      for (uint64_t q = nb; above == OctantMap::kAbsent;) {
        q = octant_key_parent(q);
        above = map_.find(q);
      }
      if (above == OctantMap::kInner) continue;
      map_.add(nb, OctantMap::kCreated);
      created_.push_back(nb);
      if (l - 1 > 0) {
        asks_[l - 1].push_back({octant_key_parent(nb), 255, true});
        unsorted_[l - 1] = true;
      }
    }
  }
  asks.clear();
}

// Each own leaf split just enough to resolve the created octants inside it.
void SubtreeBalancer::refine(const Octant& root, SubtreeLeaves* leaves) {
  out_.clear();
  const size_t bytes = descent_.payload_bytes();
  size_t pos =
      std::lower_bound(created_.begin(), created_.end(), octant_key(root)) - created_.begin();
  for (size_t i = 0; i < leaves->keys.size(); ++i) {
    const uint64_t key = leaves->keys[i];
    const std::byte* payload = leaves->payloads.data() + i * bytes;
    while (pos < created_.size() && created_[pos] <= key) ++pos;
    if (pos == created_.size() || created_[pos] >= octant_key_subtree_end(key)) {
      out_.keys.push_back(key);
      out_.payloads.insert(out_.payloads.end(), payload, payload + bytes);
      ++out_.levels[octant_key_level(key)];
      continue;
    }
    split_to_resolve(
        octant_from_key(key), false, created_.size(), [&](size_t j) { return created_[j]; }, &pos,
        [&](const Octant& o, bool is_new) { return emit_leaf(o, is_new, payload); });
  }
  out_.elements = out_.keys.size();
  int coarsest = 0;
  while (out_.levels[coarsest] == 0) ++coarsest;
  leaves->keys.swap(out_.keys);
  leaves->payloads.swap(out_.payloads);
  leaves->levels = out_.levels;
  leaves->elements = out_.elements;
  leaves->largest_edge_m = octant_edge(coarsest) * descent_.plan().tick_m;
}

// A leaf of the refinement into out_: a new one with the model's material
// at its centre (or a copy of its parent's), else as it was.
Status SubtreeBalancer::emit_leaf(const Octant& o, bool is_new, const std::byte* parent_payload) {
  const size_t bytes = descent_.payload_bytes(), at = out_.payloads.size();
  out_.keys.push_back(octant_key(o));
  out_.payloads.resize(at + bytes);
  if (is_new && fill_) {
    descent_.material(o, out_.payloads.data() + at);
  } else {
    std::memcpy(out_.payloads.data() + at, parent_payload, bytes);
  }
  ++out_.levels[o.level];
  return Status::Ok();
}

}  // namespace weaver
