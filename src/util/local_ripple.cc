#include "util/local_ripple.h"

#include <algorithm>
#include <bit>

#include "util/parent_asks.h"
#include "util/radix_sort.h"

namespace weaver {
namespace {

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

}  // namespace

// Only the leaves two levels finer than the coarsest ask (an octant of
// level l - 1 lies strictly inside a leaf only if that leaf's level is
// l - 2 or coarser), so a set graded by one level at most has nothing to
// do; and only the leaves two levels coarser than the finest go into the
// map as leaves: the others are found resolved all the same, since their
// parents are inner.
bool LocalRipple::run(const std::vector<uint64_t>& local, std::vector<uint64_t>* created,
                      size_t max_bytes) {
  created->clear();
  std::array<uint64_t, kMaxLevel + 1> count{};  // leaves by level
  for (uint64_t key : local) ++count[octant_key_level(key)];
  int coarsest = 0, finest = kMaxLevel;
  while (coarsest <= kMaxLevel && count[coarsest] == 0) ++coarsest;
  while (finest >= 0 && count[finest] == 0) --finest;
  if (finest - coarsest < 2) return true;
  // Room for the leaves it holds and their ancestors (a seventh as many,
  // where families are whole), and some created octants, without growing.
  size_t held = 0;
  for (int l = coarsest; l <= finest - 2; ++l) held += count[l];
  map_.reset(held + local.size() / 4 + 64);
  within_ = within_end_ = 0;
  uint64_t last_parent = ~uint64_t{0};
  constexpr size_t kAhead = 16;  // map slots prefetched this many leaves ahead
  for (size_t i = 0; i < local.size(); ++i) {
    if (i + kAhead < local.size()) {
      const uint64_t ahead = local[i + kAhead];
      map_.prefetch(ahead);
      if (octant_key_level(ahead) > 0) map_.prefetch(octant_key_parent(ahead));
    }
    const uint64_t key = local[i];
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
  for (int l = finest; l >= 1; --l) {
    if (!ask_level(l, created, max_bytes)) {
      for (auto& asks : asks_) asks.clear();
      unsorted_ = {};
      return false;
    }
  }
  radix_sort_by(*created, scratch_, [](uint64_t k) { return k; });
  return true;
}

size_t LocalRipple::bytes(const std::vector<uint64_t>& created) const {
  size_t n = map_.bytes() + created.capacity() * sizeof(uint64_t);
  for (const auto& asks : asks_) n += asks.capacity() * sizeof(Ask);
  return n;
}

// Neighbour nb of a level-l parent: created if it lies strictly inside a
// leaf and is not there already.
void LocalRipple::consider(uint64_t nb, int l, std::vector<uint64_t>* created) {
  if (map_.find(nb) != OctantMap::kAbsent) return;  // resolved, or created already
  // Inside the leaf (or created octant) the last walk ended at: nothing
  // inner lies between (inner octants hold leaves), so nb is created too.
  // Neighbours come in key order, so the walk is mostly saved.
  if (nb <= within_ || nb >= within_end_) {
    OctantMap::Kind above = OctantMap::kAbsent;
    uint64_t q = nb;
    while (above == OctantMap::kAbsent) {
      q = octant_key_parent(q);
      above = map_.find(q);
    }
    if (above == OctantMap::kInner) return;
    within_ = q;
    within_end_ = octant_key_subtree_end(q);
  }
  map_.add(nb, OctantMap::kCreated);
  created->push_back(nb);
  if (l - 1 > 0) {
    asks_[l - 1].push_back({octant_key_parent(nb), 255, true});
    unsorted_[l - 1] = true;
  }
}

// A leaf's ask, merged with its siblings' (they come one after another
// among the leaves of their level).
void LocalRipple::add_ask(int level, uint64_t parent, unsigned child_bit) {
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
bool LocalRipple::ask_level(int l, std::vector<uint64_t>* created, size_t max_bytes) {
  std::vector<Ask>& asks = asks_[l];
  if (unsorted_[l]) {
    radix_sort_by(asks, ask_scratch_, [](const Ask& a) { return a.parent; });
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
  // Asks go in batches: the map slots of a batch's neighbours (and their
  // parents') are prefetched together, so their cache misses overlap.
  constexpr size_t kBatch = 8;
  std::array<uint64_t, kBatch * kFaceAndEdgeDirections.size()> near;
  for (size_t b = 0; b < asks.size(); b += kBatch) {
    const size_t end = std::min(asks.size(), b + kBatch);
    size_t n = 0;
    for (size_t i = b; i < end; ++i) {
      const Ask& a = asks[i];  // (consider() may grow asks_ of level l - 1, not l)
      uint32_t asked = parent_asks::kTouchedBy[a.children];
      // The parent's siblings are there (leaves or inner) when its own
      // parent is inner, as it is above a leaf of the input: only the
      // neighbours outside it are asked about.
      if (!a.created && l >= 2) asked &= kLeavingParent[octant_key_child_id(a.parent)];
      for (uint32_t bits = asked; bits != 0; bits &= bits - 1) {
        uint64_t& nb = near[n];
        if (octant_key_neighbour(a.parent, kFaceAndEdgeDirections[std::countr_zero(bits)], &nb)) {
          map_.prefetch(nb);
          map_.prefetch(octant_key_parent(nb));
          ++n;
        }
      }
    }
    for (size_t k = 0; k < n; ++k) consider(near[k], l, created);
    if ((b & 255) == 0 && bytes(*created) > max_bytes) return false;
  }
  asks.clear();
  return true;
}

}  // namespace weaver
