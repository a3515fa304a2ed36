#include "extract/bucket_worker.h"

#include <algorithm>

#include "schema/octant.h"

namespace weaver {

Status read_bucket(LeafReader& cursor, const Bucketing& b, SpillStore& spills, BucketTask* task,
                   bool* more) {
  auto leaf_bucket = [&] { return b.of_key(octant_key_morton(cursor.key())); };
  *more = cursor.valid() || !spills.empty();
  if (!*more) return Status::Ok();
  const uint64_t next_leaf = cursor.valid() ? leaf_bucket() : UINT64_MAX;
  task->bucket = spills.empty() ? next_leaf : std::min(next_leaf, spills.first_bucket());
  task->leaf_keys.clear();
  // Only a leaf touching the bucket's far faces has corners in later buckets.
  const uint32_t bucket_edge = uint32_t{1} << (kMaxLevel - b.level);
  const uint32_t far_mask = bucket_edge - 1;
  while (cursor.valid() && leaf_bucket() == task->bucket) {
    const uint64_t key = cursor.key();
    task->leaf_keys.push_back(key);
    const Octant e = octant_from_key(key);
    const uint32_t s = octant_edge(e);
    const bool touches_far_face = s > bucket_edge || ((e.x + s) & far_mask) == 0 ||
                                  ((e.y + s) & far_mask) == 0 || ((e.z + s) & far_mask) == 0;
    if (!touches_far_face) {
      WEAVER_RETURN_IF_ERROR(cursor.next());
      continue;
    }
    for (int c = 0; c < 8; ++c) {
      const uint64_t nk = node_key(octant_corner(e, c));
      const uint64_t owner = b.of_key(nk);
      if (owner != task->bucket) {
        WEAVER_RETURN_IF_ERROR(spills.add(owner, {nk, corner_direction_bit(c)}));
      }
    }
    WEAVER_RETURN_IF_ERROR(cursor.next());
  }
  return spills.take(task->bucket, &task->incoming);
}

Status BucketWorker::run(BucketTask& t) {
  t.counts = ExtractResult{};
  t.counts.elements = t.leaf_keys.size();
  classifier_.set_local(&t.leaf_keys, t.bucket, b_.shift);
  hash_.reset(t.leaf_keys.size() + t.incoming.size() + 64);
  for (uint64_t key : t.leaf_keys) {
    const Octant e = octant_from_key(key);
    for (int c = 0; c < 8; ++c) {
      const uint64_t nk = node_key(octant_corner(e, c));
      if (b_.of_key(nk) == t.bucket) hash_.add(nk, corner_direction_bit(c));
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
