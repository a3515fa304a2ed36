#include "construct/subtree_balance.h"

#include <algorithm>
#include <array>
#include <cstring>

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

bool inside(const Octant& x, const Octant& root) {
  return x.level >= root.level && octant_ancestor(x, root.level) == root;
}

}  // namespace

SubtreeBalancer::SubtreeBalancer(const Descent& descent, bool fill_material)
    : descent_(descent), fill_(fill_material) {}

void SubtreeBalancer::balance(const Octant& root, SubtreeLeaves* leaves) {
  if (leaves->keys.empty()) return;
  grow_box(root, *leaves);
  if (stands(*leaves)) return;
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
    if (wanted(b, root)) collect(b, descent_.judge(b), root);
  }
  collected_count_ += collected_.size();
  local_.resize(collected_.size() + leaves->keys.size());
  std::merge(collected_.begin(), collected_.end(), leaves->keys.begin(), leaves->keys.end(),
             local_.begin());
  ripple_.run(local_, &created_);
  // Nothing created inside the subtree (most subtrees): its leaves stand.
  const auto inside_root = std::lower_bound(created_.begin(), created_.end(), octant_key(root));
  if (inside_root == created_.end() || *inside_root >= octant_key_subtree_end(root)) return;
  refine(leaves);
}

// Whether the balance splits none of the subtree's leaves, known without
// descending around it.  A created octant inside a leaf of level l is of
// level l + 1 or finer, and is asked for by an octant one level finer still
// (a leaf, or an octant created inside a coarser one): every chain starts
// at a leaf of level l + 2 or finer.  So where the subtree's leaves span
// two levels at most, m (the coarsest) and m + 1, its leaves stand unless
// some leaf of level m + 2 meets the grown box (grow_box, already run).  Such a leaf's
// ancestor of level m + 1 was split, and lies in the grown box (whose
// sides are on the grid of level m + 1: the root's, a leaf's edge of level
// m or m + 1, the domain's blocks), here widened by its edge all the same,
// so as not to rest on that: if the model's bounds over the box keep every
// octant of level m + 1 a leaf (judge() splits none whose samples lie in
// it), there is none.  At 1 Hz, 83% of the basin's subtrees (40% of its
// leaves) are of two levels, and a leaf around the subtrees was descended
// again for 19% of the leaves instead of 36%.
bool SubtreeBalancer::stands(const SubtreeLeaves& leaves) const {
  int coarsest = 0, finest = kMaxLevel;
  while (coarsest < kMaxLevel && leaves.levels[coarsest] == 0) ++coarsest;
  while (finest > 0 && leaves.levels[finest] == 0) --finest;
  if (finest - coarsest >= 2) return false;
  if (coarsest + 1 > kMaxLevel) return true;  // nothing can be finer than level 20
  const ConstructPlan& p = descent_.plan();
  const int64_t e = octant_edge(coarsest + 1);
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    // The domain bounds the wider box too: the octants of level m + 1 are
    // finer than the blocks, so each lies in one.
    const int64_t domain_end = int64_t{p.blocks[a]} * octant_edge(p.block_level);
    lo[a] = double(std::max<int64_t>(0, box_lo_[a] - e)) * p.tick_m;
    hi[a] = double(std::min<int64_t>(domain_end, box_hi_[a] + e)) * p.tick_m;
  }
  return descent_.keeps_level_within(coarsest + 1, lo, hi);
}

// The subtree's box grown on each side by the edge of the largest own leaf
// touching that side (the descent noted them), within the domain.
void SubtreeBalancer::grow_box(const Octant& root, const SubtreeLeaves& leaves) {
  const int64_t r_lo[3] = {root.x, root.y, root.z};
  const int64_t r_edge = octant_edge(root);
  const ConstructPlan& p = descent_.plan();
  for (int a = 0; a < 3; ++a) {
    const int64_t domain_end = int64_t{p.blocks[a]} * octant_edge(p.block_level);
    box_lo_[a] = std::max<int64_t>(0, r_lo[a] - leaves.border_lo[a]);
    box_hi_[a] = std::min<int64_t>(domain_end, r_lo[a] + r_edge + leaves.border_hi[a]);
  }
}

bool SubtreeBalancer::wanted(const Octant& x, const Octant& root) const {
  return meets(x, box_lo_, box_hi_) && !inside(x, root);
}

// The input leaves under x that meet the grown box, outside root, into
// collected_ in key order; j is the descent's judgement of x.
void SubtreeBalancer::collect(const Octant& x, const Judgement& j, const Octant& root) {
  if (!j.split) {
    collected_.push_back(octant_key(x));
    return;
  }
  if (const int level = descent_.uniform_leaf_level(x, j); level > 0) {
    collect_level(x, level, root);
    return;
  }
  bool want[8];
  for (int c = 0; c < 8; ++c) want[c] = wanted(octant_child(x, c), root);
  Judgement children[8];
  descent_.judge_children(x, j, want, children);
  for (int c = 0; c < 8; ++c) {
    if (want[c]) collect(octant_child(x, c), children[c], root);
  }
}

void SubtreeBalancer::collect_level(const Octant& x, int level, const Octant& root) {
  if (x.level == level) {
    collected_.push_back(octant_key(x));
    return;
  }
  for (int c = 0; c < 8; ++c) {
    const Octant child = octant_child(x, c);
    if (wanted(child, root)) collect_level(child, level, root);
  }
}

// Each own leaf split just enough to resolve the created octants inside it.
// The leaves between two split ones stay where they are, a piece of the
// subtree's leaves (descent.h); a split's leaves are added, each first
// with its parent leaf's record, and, where the model fills new leaves,
// its material after the walk: eight siblings from one lattice of their
// centres (most splits make whole sibling groups), any other leaf alone.
void SubtreeBalancer::refine(SubtreeLeaves* leaves) {
  fresh_.clear();
  copied_.clear();
  const size_t bytes = descent_.payload_bytes();
  const bool carved = descent_.plan().carved;
  const uint64_t* keys = leaves->keys.data();
  const std::byte* payloads = leaves->payloads.data();
  auto piece = [leaves](bool added, size_t begin, size_t end) {
    auto& p = leaves->pieces;
    if (!p.empty() && p.back().added == added && p.back().end == begin) {
      p.back().end = end;
    } else {
      p.push_back({added, begin, end});
    }
  };
  auto keep_run = [&](size_t begin, size_t end) {
    if (begin < end) piece(false, begin, end);
    return Status::Ok();
  };
  size_t last_split = SIZE_MAX;
  resolve_leaves(keys, leaves->keys.size(), created_, keep_run,
                 [&](size_t i, uint64_t key, bool is_new) {
                   if (i != last_split) {  // the first leaf of i's split
                     last_split = i;
                     --leaves->levels[octant_key_level(keys[i])];
                     --leaves->elements;
                   }
                   // A part of a leaf wholly on one side of the ground is on it too.
                   if (carved) leaves->added_sides.push_back(leaves->sides[i]);
                   const size_t at = leaves->added_keys.size();
                   add_leaf(leaves, key, is_new, payloads + i * bytes);
                   piece(true, at, at + 1);
                   return Status::Ok();
                 });
  fill_materials(leaves);
  int coarsest = 0;
  while (leaves->levels[coarsest] == 0) ++coarsest;
  leaves->largest_edge_m = octant_edge(coarsest) * descent_.plan().tick_m;
}

// A leaf of a split onto the added leaves: a new one is noted, to take
// the model's material at its centre where it fills; any other is to take
// its parent's record.  The records are made once the walk is done (a
// copy of each parent's record first, in a call a leaf, was 1.2% of the 2
// Hz construct's samples, and the model then replaced it).
void SubtreeBalancer::add_leaf(SubtreeLeaves* leaves, uint64_t key, bool is_new,
                               const std::byte* parent_payload) {
  const size_t at = leaves->added_keys.size();
  if (is_new && fill_) {
    fresh_.push_back(at);
  } else {
    copied_.push_back({at, parent_payload});
  }
  leaves->added_keys.push_back(key);
  ++leaves->levels[octant_key_level(key)];
  ++leaves->elements;
}

// The added leaves' records: a copy of the parent's for those noted so,
// the model's material for each new leaf noted, by sibling groups where
// all eight are new and one after another.
void SubtreeBalancer::fill_materials(SubtreeLeaves* leaves) {
  const size_t bytes = descent_.payload_bytes();
  const auto& keys = leaves->added_keys;
  leaves->added_payloads.resize(keys.size() * bytes);
  for (const auto& [at, parent] : copied_) {
    std::memcpy(leaves->added_payloads.data() + at * bytes, parent, bytes);
  }
  for (size_t f = 0; f < fresh_.size();) {
    const size_t at = fresh_[f];
    const uint64_t key = keys[at];
    std::byte* payload = leaves->added_payloads.data() + at * bytes;
    // fresh_ rises by one at least an entry: eight entries spanning eight
    // places are those places, and eight leaves of one parent its children.
    if (f + 8 <= fresh_.size() && fresh_[f + 7] == at + 7 && octant_key_child_id(key) == 0 &&
        octant_key_parent(keys[at + 7]) == octant_key_parent(key)) {
      descent_.children_materials(octant_from_key(octant_key_parent(key)), payload);
      f += 8;
    } else {
      descent_.material(octant_from_key(key), payload);
      ++f;
    }
  }
}

}  // namespace weaver
