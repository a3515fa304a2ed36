#include "extract/bucket_worker.h"

#include <algorithm>
#include <bit>

#include "schema/octant.h"

namespace weaver {

void leaf_corner_keys(uint64_t leaf_key, uint64_t out[8]) {
  const int bit = kMaxLevel - octant_key_level(leaf_key);
  out[0] = octant_key_morton(leaf_key);
  out[1] = morton_step(out[0], 0, bit);
  out[2] = morton_step(out[0], 1, bit);
  out[3] = morton_step(out[1], 1, bit);
  for (int k = 0; k < 4; ++k) out[k + 4] = morton_step(out[k], 2, bit);
}

Status BucketReader::next(BucketTask* task, bool* more) {
  *more = !finished_ && (cursor_.valid() || !carry_.empty());
  if (!*more) return Status::Ok();
  task->leaf_keys.clear();
  task->start = next_start_;
  WEAVER_RETURN_IF_ERROR(policy_.level >= 0 ? gather_aligned(task) : gather_counted(task));
  next_start_ = task->end;
  finished_ = task->end == UINT64_MAX;
  task->incoming.clear();
  WEAVER_RETURN_IF_ERROR(spills_.take_below(task->end, &task->incoming));
  return spill_far_corners(*task);
}

// The paper's S2: the leaves under one aligned octant of the policy's level.
Status BucketReader::gather_aligned(BucketTask* task) {
  const int shift = 3 * (kMaxLevel - policy_.level);
  const uint64_t bucket = octant_key_morton(cursor_.key()) >> shift;
  while (cursor_.valid() && (octant_key_morton(cursor_.key()) >> shift) == bucket) {
    task->leaf_keys.push_back(cursor_.key());
    WEAVER_RETURN_IF_ERROR(cursor_.next());
  }
  task->end = cursor_.valid() ? octant_key_morton(cursor_.key()) : UINT64_MAX;
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
  while (leaves.size() < window && cursor_.valid()) {
    leaves.push_back(cursor_.key());
    WEAVER_RETURN_IF_ERROR(cursor_.next());
  }
  if (leaves.size() < window) {  // the table's last leaves
    task->end = UINT64_MAX;
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
  if (task.end == UINT64_MAX) return Status::Ok();
  run_.clear();
  uint64_t corners[8];
  for (uint64_t key : task.leaf_keys) {
    const int bit = kMaxLevel - octant_key_level(key);
    const uint64_t m = octant_key_morton(key);
    // Corner 7 has the largest key: below the end, all are.
    if (morton_step(morton_step(morton_step(m, 0, bit), 1, bit), 2, bit) < task.end) continue;
    leaf_corner_keys(key, corners);
    for (int c = 0; c < 8; ++c) {
      if (corners[c] >= task.end) run_.push_back({corners[c], corner_direction_bit(c)});
    }
  }
  std::sort(run_.begin(), run_.end(),
            [](const SpillRecord& a, const SpillRecord& b) { return a.key < b.key; });
  size_t kept = 0;
  for (size_t i = 0; i < run_.size(); ++i) {
    if (kept > 0 && run_[kept - 1].key == run_[i].key) {
      run_[kept - 1].mask |= run_[i].mask;
    } else {
      run_[kept++] = run_[i];
    }
  }
  run_.resize(kept);
  return spills_.add_run(std::vector<SpillRecord>(run_.begin(), run_.end()));
}

Status BucketWorker::run(BucketTask& t) {
  t.counts = ExtractResult{};
  t.counts.elements = t.leaf_keys.size();
  classifier_.set_local(&t.leaf_keys, t.start, t.end);
  hash_.reset(t.leaf_keys.size() + t.incoming.size() + 64);
  uint64_t corners[8];
  for (uint64_t key : t.leaf_keys) {
    leaf_corner_keys(key, corners);
    for (int c = 0; c < 8; ++c) {
      if (corners[c] < t.end) hash_.add(corners[c], corner_direction_bit(c));
    }
  }
  for (const SpillRecord& r : t.incoming) hash_.add(r.key, r.mask);
  sorted_.resize(hash_.size());
  for (size_t i = 0; i < hash_.size(); ++i) sorted_[i] = {hash_.key_at(i), hash_.mask_at(i)};
  std::sort(sorted_.begin(), sorted_.end(),
            [](const SpillRecord& a, const SpillRecord& b) { return a.key < b.key; });
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
