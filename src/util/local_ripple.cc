#include "util/local_ripple.h"

#include <algorithm>
#include <bit>
#include <queue>
#include <utility>

#include "util/parallel.h"
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

// Candidates are settled this many at a time: their sort stays in the
// cache, and a level's candidates (many times its created octants) never
// take more memory than this.
constexpr size_t kChunk = size_t{1} << 17;

// Sorts keys of octants of one level (level >= 1): only their Morton bits
// above the level's cell differ.
void sort_level_keys(std::vector<uint64_t>& keys, int level, std::vector<uint64_t>& scratch) {
  if (keys.size() < 512) {
    std::sort(keys.begin(), keys.end());
  } else {
    radix_sort(keys, 64 - 3 * level, 3 * level, scratch);
  }
}

void sort_unique(std::vector<uint64_t>& keys, int level, std::vector<uint64_t>& scratch) {
  sort_level_keys(keys, level, scratch);
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

// A level's asks are shared between threads only where there are this
// many: below it, a thread's start costs more than half the work.
constexpr size_t kSharedAsks = size_t{1} << 14;

// Sorted ranges (none sharing a key) merged into out, in key order.
void merge_ranges(const std::vector<std::pair<const uint64_t*, const uint64_t*>>& ranges,
                  uint64_t* out) {
  using Head = std::pair<uint64_t, size_t>;  // a range's next key, and which range
  std::priority_queue<Head, std::vector<Head>, std::greater<Head>> heads;
  std::vector<const uint64_t*> at;
  for (size_t r = 0; r < ranges.size(); ++r) {
    at.push_back(ranges[r].first);
    if (ranges[r].first != ranges[r].second) heads.push({*ranges[r].first, r});
  }
  while (!heads.empty()) {
    const size_t r = heads.top().second;
    heads.pop();
    // Take this range's keys while they come before every other head.
    const uint64_t bound = heads.empty() ? UINT64_MAX : heads.top().first;
    const uint64_t* p = at[r];
    while (p != ranges[r].second && *p < bound) *out++ = *p++;
    at[r] = p;
    if (p != ranges[r].second) heads.push({*p, r});
  }
}

// Whether keys[0..8) are a parent's eight children (keys[0] its child 0).
bool whole_siblings(const uint64_t* keys, uint64_t stride) {
  bool whole = true;
  for (int c = 1; c < 8; ++c) whole &= keys[c] == keys[0] + c * stride;
  return whole;
}

}  // namespace

// Only the leaves two levels finer than the coarsest ask (an octant of
// level l - 1 lies strictly inside a leaf only if that leaf's level is
// l - 2 or coarser), so a set graded by one level at most has nothing to
// do; and only the leaves two levels coarser than the finest can hold a
// created octant.
bool LocalRipple::run(const std::vector<uint64_t>& local, std::vector<uint64_t>* created,
                      size_t max_bytes) {
  created->clear();
  // The levels present, a bit each: counting the leaves of each level
  // waited on each count's last increment (3% of the 2 Hz construct).
  uint32_t present = 0;
  for (uint64_t key : local) present |= uint32_t{1} << octant_key_level(key);
  if (present == 0) return true;
  const int coarsest = std::countr_zero(present), finest = 31 - std::countl_zero(present);
  if (finest - coarsest < 2) return true;
  gather(local, coarsest, finest);
  made_from_ = 0;
  runs_.assign(1, 0);
  bool fitted = true;
  for (int l = finest; l >= coarsest + 2 && fitted; --l) {
    fitted = ask_level(l, created, max_bytes);
    runs_.push_back(created->size());
  }
  for (auto& asks : leaf_asks_) asks.clear();
  if (!fitted) return false;
  merge_runs(created);
  return true;
}

// *created's runs (a level's created octants each, in key order) merged
// into one; on two threads where there are many, each taking the keys on
// one side of the middle key of the longest run.
void LocalRipple::merge_runs(std::vector<uint64_t>* created) {
  const size_t n = created->size();
  if (runs_.size() <= 2 || n < 2) return;
  if (lanes_ == 1 || n < kSharedAsks) {
    merge_pairs(created);
    return;
  }
  size_t longest = 0;
  for (size_t r = 0; r + 1 < runs_.size(); ++r) {
    if (runs_[r + 1] - runs_[r] > runs_[longest + 1] - runs_[longest]) longest = r;
  }
  const uint64_t middle = (*created)[(runs_[longest] + runs_[longest + 1]) / 2];
  using Range = std::pair<const uint64_t*, const uint64_t*>;
  std::vector<Range> below, above;
  const uint64_t* c = created->data();
  size_t below_count = 0;
  for (size_t r = 0; r + 1 < runs_.size(); ++r) {
    const uint64_t* cut = std::lower_bound(c + runs_[r], c + runs_[r + 1], middle);
    below.push_back({c + runs_[r], cut});
    above.push_back({cut, c + runs_[r + 1]});
    below_count += cut - (c + runs_[r]);
  }
  scratch_.resize(n);
  run_shares(2, [&](int half) {
    merge_ranges(half == 0 ? below : above, scratch_.data() + (half == 0 ? 0 : below_count));
    return Status::Ok();
  });
  created->swap(scratch_);
}

// *created's runs merged two by two, round after round, between it and
// scratch_: a few passes over the octants where a radix sort of them made
// a count and a scatter pass for each 11 bits that differ (about 30 in a
// subtree).
void LocalRipple::merge_pairs(std::vector<uint64_t>* created) {
  std::vector<size_t> bounds = {0}, next;
  for (size_t r = 1; r < runs_.size(); ++r) {
    if (runs_[r] > bounds.back()) bounds.push_back(runs_[r]);
  }
  scratch_.resize(created->size());
  while (bounds.size() > 2) {
    const uint64_t* from = created->data();
    uint64_t* to = scratch_.data();
    next.assign(1, 0);
    for (size_t i = 0; i + 1 < bounds.size(); i += 2) {
      const size_t a = bounds[i], b = bounds[i + 1];
      const size_t c = i + 2 < bounds.size() ? bounds[i + 2] : b;
      std::merge(from + a, from + b, from + b, from + c, to + a);
      next.push_back(c);
    }
    created->swap(scratch_);
    bounds.swap(next);
  }
}

size_t LocalRipple::bytes(const std::vector<uint64_t>& created) const {
  size_t n = (holders_.capacity() + scratch_.capacity() + created.capacity()) * sizeof(uint64_t) +
             asks_.capacity() * sizeof(Ask);
  for (const auto& asks : leaf_asks_) n += asks.capacity() * sizeof(Ask);
  for (const Lane& lane : lane_) n += lane.bytes();
  return n;
}

// The holders, and the leaves' asks by level, merged by parent (siblings
// come one after another among the leaves of their level).
void LocalRipple::gather(const std::vector<uint64_t>& local, int coarsest, int finest) {
  holders_.clear();
  const size_t n = local.size();
  for (size_t i = 0; i < n;) {
    const uint64_t key = local[i];
    const int level = octant_key_level(key);
    // Eight siblings whole, the common case (a parent split once): their
    // keys a stride apart from its child 0.  Taken at once.
    if (level < kMaxLevel && i + 8 <= n && octant_key_child_id(key) == 0 &&
        whole_siblings(&local[i], octant_key_stride(level))) {
      if (level <= finest - 2) holders_.insert(holders_.end(), &local[i], &local[i] + 8);
      if (level >= coarsest + 2) leaf_asks_[level].push_back({octant_key_parent(key), 255, false});
      i += 8;
      continue;
    }
    ++i;
    if (level <= finest - 2) holders_.push_back(key);
    if (level < coarsest + 2) continue;
    const uint64_t parent = octant_key_parent(key);
    const uint32_t bit = 1u << octant_key_child_id(key);
    std::vector<Ask>& asks = leaf_asks_[level];
    if (!asks.empty() && asks.back().parent == parent) {
      asks.back().children |= bit;
    } else {
      asks.push_back({parent, bit, false});
    }
  }
}

// Level l's asks in key order: the leaves' and those of the parents of
// the octants created at level l (the tail of *created, from made_from_),
// which ask for all their neighbours.
void LocalRipple::merge_asks(int l, const std::vector<uint64_t>& created) {
  asks_.clear();
  auto push = [&](const Ask& a) {
    if (!asks_.empty() && asks_.back().parent == a.parent) {
      asks_.back().children |= a.children;
      asks_.back().created |= a.created;
    } else {
      asks_.push_back(a);
    }
  };
  const std::vector<Ask>& leaves = leaf_asks_[l];
  size_t i = 0;
  for (size_t m = made_from_; m < created.size(); ++m) {
    const uint64_t parent = octant_key_parent(created[m]);
    while (i < leaves.size() && leaves[i].parent <= parent) push(leaves[i++]);
    push({parent, 255, true});
  }
  while (i < leaves.size()) push(leaves[i++]);
}

// Level l's asks: each candidate of level l - 1 that lies strictly inside
// a leaf is created (appended to *created, in key order), and asks in turn
// at level l - 1.  Where there are many asks, two threads take a half
// each, and their octants are merged.
bool LocalRipple::ask_level(int l, std::vector<uint64_t>* created, size_t max_bytes) {
  merge_asks(l, *created);
  const size_t lanes = asks_.size() >= kSharedAsks ? lanes_ : 1;
  const Ask* asks = asks_.data();
  const size_t n = asks_.size();
  run_shares(static_cast<int>(lanes), [&](int i) {
    lane_[i].take(asks + n * i / lanes, asks + n * (i + 1) / lanes, l, holders_);
    return Status::Ok();
  });
  made_from_ = created->size();
  if (lanes == 1) {
    created->insert(created->end(), lane_[0].made.begin(), lane_[0].made.end());
  } else {
    const std::vector<uint64_t>&a = lane_[0].made, &b = lane_[1].made;
    created->resize(made_from_ + a.size() + b.size());
    const auto end = std::set_union(a.begin(), a.end(), b.begin(), b.end(),
                                    created->begin() + static_cast<ptrdiff_t>(made_from_));
    created->erase(end, created->end());
  }
  return bytes(*created) <= max_bytes;
}

// The candidates of asks [begin, end) of level l, settled a chunk at a
// time into made (sorted, once each).
void LocalRipple::Lane::take(const Ask* begin, const Ask* end, int l,
                             const std::vector<uint64_t>& holders) {
  made.clear();
  candidates.clear();
  recent.clear();
  bool several = false;  // chunks settled: made is in order within each
  // Each neighbour is stored past the last candidate and kept by moving the
  // count, not by a branch: whether the recent keys hold it is a coin toss
  // to the predictor (its mispredictions were a third of this loop).
  size_t count = 0;
  for (const Ask* a = begin; a != end; ++a) {
    uint32_t asked = parent_asks::kTouchedBy[a->children];
    // The parent's siblings are there (leaves or inner) when its own
    // parent is inner, as it is above a leaf of the input: only the
    // neighbours outside it are asked about.
    if (!a->created && l >= 2) asked &= kLeavingParent[octant_key_child_id(a->parent)];
    if (candidates.size() < count + kFaceAndEdgeDirections.size()) {
      candidates.resize(std::max(2 * candidates.size(), count + 64));
    }
    uint64_t* out = candidates.data();
    const KeyNeighbours around(a->parent);  // each axis stepped once, not once a neighbour
    for (uint32_t bits = asked; bits != 0; bits &= bits - 1) {
      uint64_t nb = 0;
      const bool in_root = around.neighbour(kFaceAndEdgeDirections[std::countr_zero(bits)], &nb);
      // (Outside the root nb is 0, the root's key: no candidate's, whose
      // level is at least 1, so putting it among the recent keys only
      // lets a repeat through.)
      const bool fresh = !recent.seen(nb);
      out[count] = nb;
      count += in_root & fresh;
    }
    if (count >= kChunk) {
      candidates.resize(count);
      settle(l - 1, holders);
      count = 0;
      several = true;
    }
  }
  candidates.resize(count);
  settle(l - 1, holders);
  if (several) sort_unique(made, l - 1, scratch);
}

// The candidates (octants of `level`) that lie strictly inside a holder,
// onto made: sorted, each one's holder is the last leaf at or before it,
// found by walking the holders forwards (in strides, then halving, as the
// candidates are often sparse among them).
void LocalRipple::Lane::settle(int level, const std::vector<uint64_t>& holders) {
  if (candidates.empty()) return;
  sort_unique(candidates, level, scratch);
  const uint64_t* h = holders.data();
  const size_t n = holders.size();
  size_t past = std::upper_bound(h, h + n, candidates.front()) - h;  // holders <= the candidate
  for (uint64_t k : candidates) {
    if (past < n && h[past] <= k) {
      size_t step = 1;
      while (past + step < n && h[past + step] <= k) step *= 2;
      past = std::upper_bound(h + past + step / 2 + 1, h + std::min(n, past + step), k) - h;
    }
    if (past == 0) continue;
    const uint64_t holder = h[past - 1];
    if (octant_key_level(holder) < level && k < octant_key_subtree_end(holder)) made.push_back(k);
  }
  candidates.clear();
}

size_t LocalRipple::Lane::bytes() const {
  return (candidates.capacity() + scratch.capacity() + made.capacity()) * sizeof(uint64_t);
}

}  // namespace weaver
