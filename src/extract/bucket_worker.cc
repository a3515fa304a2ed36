#include "extract/bucket_worker.h"

#include <algorithm>
#include <array>
#include <bit>

#include "schema/octant.h"
#include "util/radix_sort.h"

namespace weaver {

void leaf_corner_keys(uint64_t leaf_key, uint64_t out[8]) {
  const int bit = kMaxLevel - octant_key_level(leaf_key);
  out[0] = octant_key_morton(leaf_key);
  out[1] = morton_step(out[0], 0, bit);
  out[2] = morton_step(out[0], 1, bit);
  out[3] = morton_step(out[1], 1, bit);
  for (int k = 0; k < 4; ++k) out[k + 4] = morton_step(out[k], 2, bit);
}

namespace {

// Where the last bucket of leaves ends: where its last leaf does.  Not
// sooner (a bucket's range holds whole leaves: the classifier looks no
// further for a leaf holding a pixel in it), and not later: the nodes past
// it wait for the tail (gather_tail).
uint64_t leaves_end(const std::vector<uint64_t>& leaves) {
  const uint64_t last = leaves.back();
  return octant_key_morton(last) + (uint64_t{1} << (3 * (kMaxLevel - octant_key_level(last))));
}

}  // namespace

uint64_t BucketReader::end_after(const std::vector<uint64_t>& leaves) const {
  return cursor_.valid() ? octant_key_morton(cursor_.key()) : leaves_end(leaves);
}

Status BucketReader::next(BucketTask* task, bool* more) {
  const bool leaves_left = at_leaf() || !carry_.empty();
  // A part before the table's end has no tail: its spills left at the end
  // are the later parts' (and reached them before: extract_shard).
  *more = leaves_left || (policy_.stop == UINT64_MAX && !spills_.empty());
  if (!*more) return Status::Ok();
  task->leaf_keys.clear();
  task->incoming.clear();
  task->start = next_start_;
  if (!leaves_left) return gather_tail(task);
  WEAVER_RETURN_IF_ERROR(policy_.level >= 0 ? gather_aligned(task) : gather_counted(task));
  next_start_ = task->end;
  WEAVER_RETURN_IF_ERROR(spills_.take_below(task->end, &task->incoming));
  return spill_far_corners(*task);
}

Status BucketReader::gather_tail(BucketTask* task) {
  // A bucket of K leaves has about 1.5 K nodes (the paper's buckets by
  // level set no K: theirs take 1536).
  const uint64_t nodes = std::max<uint64_t>(policy_.leaves, 1024) * 3 / 2;
  WEAVER_RETURN_IF_ERROR(spills_.take_first(nodes, &task->end, &task->incoming));
  next_start_ = task->end;
  return Status::Ok();
}

// The paper's S2: the leaves under one aligned octant of the policy's level.
Status BucketReader::gather_aligned(BucketTask* task) {
  const int shift = 3 * (kMaxLevel - policy_.level);
  const uint64_t bucket = octant_key_morton(cursor_.key()) >> shift;
  while (at_leaf() && (octant_key_morton(cursor_.key()) >> shift) == bucket) {
    task->leaf_keys.push_back(cursor_.key());
    WEAVER_RETURN_IF_ERROR(cursor_.next());
  }
  task->end = end_after(task->leaf_keys);
  return Status::Ok();
}

// About policy_.leaves leaves: reads a quarter more, then cuts before the
// leaf whose Morton code has the most trailing zeros (the coarsest aligned
// boundary in that window); the leaves past the cut start the next bucket.
Status BucketReader::gather_counted(BucketTask* task) {
  std::vector<uint64_t>& leaves = task->leaf_keys;
  leaves.swap(carry_);
  const size_t want = std::max<uint64_t>(policy_.leaves, 1);
  const size_t window = want + std::max<size_t>(want / 4, 1);
  while (leaves.size() < window && at_leaf()) {
    leaves.push_back(cursor_.key());
    WEAVER_RETURN_IF_ERROR(cursor_.next());
  }
  if (leaves.size() < window) {
    task->end = end_after(leaves);  // the part's (or the table's) last leaves
    return Status::Ok();
  }
  size_t cut = want;
  int best = -1;
  for (size_t i = want; i < leaves.size(); ++i) {
    const int zeros = std::countr_zero(octant_key_morton(leaves[i]));
    if (zeros > best) best = zeros, cut = i;
  }
  carry_.assign(leaves.begin() + static_cast<ptrdiff_t>(cut), leaves.end());
  leaves.resize(cut);
  task->end = octant_key_morton(carry_.front());
  return Status::Ok();
}

// Hands the corners of the bucket's leaves at or past its end to the spill
// store, as one run sorted by key with duplicates merged.
Status BucketReader::spill_far_corners(const BucketTask& task) {
  // Every far corner goes in the scratch, which is reused; the run keeps
  // them with duplicates merged, in a buffer of just their size (the spill
  // store holds thousands of runs).
  std::vector<SpillRecord>& run = far_corners_;
  run.clear();
  uint64_t corners[8];
  for (uint64_t key : task.leaf_keys) {
    const int bit = kMaxLevel - octant_key_level(key);
    const uint64_t m = octant_key_morton(key);
    // Corner 7 has the largest key: below the end, all are.
    if (morton_step(morton_step(morton_step(m, 0, bit), 1, bit), 2, bit) < task.end) continue;
    leaf_corner_keys(key, corners);
    for (int c = 0; c < 8; ++c) {
      if (corners[c] >= task.end) run.push_back({corners[c], corner_direction_bit(c)});
    }
  }
  sort_and_merge(run, packed_, scratch_);
  return spills_.add_run(std::vector<SpillRecord>(run.begin(), run.end()));
}

void sort_and_merge(std::vector<SpillRecord>& run, std::vector<uint64_t>& packed,
                    std::vector<uint64_t>& scratch) {
  sort_records(run, packed, scratch);
  size_t kept = 0;
  for (size_t i = 0; i < run.size(); ++i) {
    if (kept > 0 && run[kept - 1].key == run[i].key) {
      run[kept - 1].mask |= run[i].mask;
    } else {
      run[kept++] = run[i];
    }
  }
  run.resize(kept);
}

namespace {

// Whether the 8 leaves from `first` on, in key order, are the 8 children of
// one parent: children 0 and 7, with 6 leaves of their level between.  (The
// levels matter where leaves need not fill their parents: with holes, 6
// finer leaves can sit between two children.)
bool siblings(const uint64_t* first) {
  const int level = octant_key_level(first[0]);
  if (level == 0) return false;
  for (int i = 1; i < 8; ++i) {
    if (octant_key_level(first[i]) != level) return false;
  }
  const int bits = 3 * (kMaxLevel - level);
  const uint64_t m = octant_key_morton(first[0]);
  return ((m >> bits) & 7) == 0 && octant_key_morton(first[7]) == m + (uint64_t{7} << bits);
}

// The direction mask of lattice point (a, b, c), each 0..2, of a complete
// sibling group: the cells around it that are children.  On an axis where
// the point is at 0 only the + cell is, at 2 only the - cell, at 1 both.
constexpr std::array<uint8_t, 27> lattice_masks() {
  std::array<uint8_t, 27> masks{};
  for (int p = 0; p < 27; ++p) {
    const int at[3] = {p % 3, p / 3 % 3, p / 9};
    for (int d = 0; d < 8; ++d) {
      bool child = true;
      for (int axis = 0; axis < 3; ++axis) {
        const int side = (d >> axis) & 1;
        child = child && !(at[axis] == 0 && side == 0) && !(at[axis] == 2 && side == 1);
      }
      if (child) masks[p] |= static_cast<uint8_t>(1u << d);
    }
  }
  return masks;
}
constexpr std::array<uint8_t, 27> kLatticeMasks = lattice_masks();

}  // namespace

// The 27 corners of a complete sibling group (child 0's key given), each
// once with the bits of all 8 children: a third of the hash updates of
// adding the 8 leaves' corners one by one.
void BucketWorker::add_sibling_lattice(uint64_t child0, uint64_t end) {
  const int bit = kMaxLevel - octant_key_level(child0);
  uint64_t keys[27];
  keys[0] = octant_key_morton(child0);
  for (int p = 1; p < 27; ++p) {
    const int axis = p % 3 != 0 ? 0 : p % 9 != 0 ? 1 : 2;
    const int back = axis == 0 ? 1 : axis == 1 ? 3 : 9;  // the point one step lower on axis
    keys[p] = morton_step(keys[p - back], axis, bit);
  }
  for (int p = 0; p < 27; ++p) {
    if (keys[p] < end) hash_.add(keys[p], kLatticeMasks[p]);
  }
}

// Sorts records by key.  A radix sort on the keys' offsets from the
// smallest, less their common trailing zero bits (corners are multiples of
// the finest leaves' edge), packed with the mask into one word; std::sort if
// they do not fit in 56 bits.
void sort_records(std::vector<SpillRecord>& records, std::vector<uint64_t>& packed,
                  std::vector<uint64_t>& scratch) {
  const size_t n = records.size();
  if (n < 2) return;
  uint64_t lo = UINT64_MAX, hi = 0;
  for (const SpillRecord& r : records) {
    lo = std::min(lo, r.key);
    hi = std::max(hi, r.key);
  }
  uint64_t offsets = 0;
  for (const SpillRecord& r : records) offsets |= r.key - lo;
  const int zeros = offsets == 0 ? 0 : std::countr_zero(offsets);
  const int bits = std::bit_width((hi - lo) >> zeros);
  if (bits > 56) {
    std::sort(records.begin(), records.end(),
              [](const SpillRecord& a, const SpillRecord& b) { return a.key < b.key; });
    return;
  }
  packed.resize(n);
  for (size_t i = 0; i < n; ++i)
    packed[i] = ((records[i].key - lo) >> zeros) << 8 | records[i].mask;
  radix_sort(packed, 8, bits, scratch);
  for (size_t i = 0; i < n; ++i) {
    records[i] = {((packed[i] >> 8) << zeros) + lo, static_cast<uint8_t>(packed[i])};
  }
}

Status BucketWorker::run(BucketTask& t) {
  t.counts = ExtractResult{};
  t.counts.elements = t.leaf_keys.size();
  classifier_.set_local(&t.leaf_keys, t.start, t.end);
  // Up to about 1.5 nodes a leaf (a randomly refined octree's dangling
  // nodes); sized for them, the table never grows mid-bucket.
  hash_.reset(t.leaf_keys.size() * 3 / 2 + t.incoming.size() + 64);
  uint64_t corners[8];
  const std::vector<uint64_t>& leaves = t.leaf_keys;
  for (size_t i = 0; i < leaves.size();) {
    if (i + 8 <= leaves.size() && siblings(&leaves[i])) {
      add_sibling_lattice(leaves[i], t.end);
      i += 8;
      continue;
    }
    leaf_corner_keys(leaves[i++], corners);
    for (int c = 0; c < 8; ++c) {
      if (corners[c] < t.end) hash_.add(corners[c], corner_direction_bit(c));
    }
  }
  for (const SpillRecord& r : t.incoming) hash_.add(r.key, r.mask);
  sorted_.resize(hash_.size());
  for (size_t i = 0; i < hash_.size(); ++i) sorted_[i] = {hash_.key_at(i), hash_.mask_at(i)};
  sort_records(sorted_, packed_, scratch_);
  t.node_keys.resize(sorted_.size());
  t.node_kinds.resize(sorted_.size());
  for (size_t i = 0; i < sorted_.size(); ++i) {
    NodeKind kind = NodeKind::kAnchored;
    WEAVER_RETURN_IF_ERROR(classifier_.classify(sorted_[i].key, sorted_[i].mask, &kind));
    t.node_keys[i] = sorted_[i].key;
    t.node_kinds[i] = static_cast<std::byte>(kind);
    count_kind(kind, &t.counts);
  }
  return Status::Ok();
}

}  // namespace weaver
