#include "mesh/corner_batch.h"

#include <algorithm>
#include <string>

#include "schema/node.h"

namespace weaver {

// LSD radix sort of the pairs on the key's 63 bits, 11 bits a pass, stable.
void CornerBatch::sort_by_key() {
  constexpr int kDigit = 11;
  constexpr size_t kBuckets = size_t{1} << kDigit;
  scratch_.resize(pairs_.size());
  uint64_t all = 0;
  for (const KeySlot& p : pairs_) all |= p.key;
  for (int shift = 0; shift < 64 && (all >> shift) != 0; shift += kDigit) {
    size_t count[kBuckets] = {};
    for (const KeySlot& p : pairs_) ++count[(p.key >> shift) & (kBuckets - 1)];
    size_t sum = 0;
    for (size_t& c : count) {
      const size_t n = c;
      c = sum;
      sum += n;
    }
    for (const KeySlot& p : pairs_) scratch_[count[(p.key >> shift) & (kBuckets - 1)]++] = p;
    pairs_.swap(scratch_);
  }
}

Status CornerBatch::resolve(BTree& nodes, const std::vector<Octant>& elements,
                            std::vector<std::array<uint64_t, 8>>* ids) {
  pairs_.clear();
  for (size_t i = 0; i < elements.size(); ++i) {
    for (int k = 0; k < 8; ++k)
      pairs_.push_back({node_key(octant_corner(elements[i], k)), 8 * i + k});
  }
  sort_by_key();
  ids->resize(elements.size());
  leaf_.clear();
  auto pos = leaf_.begin();
  uint64_t last = 0, rank = 0;
  for (size_t i = 0; i < pairs_.size(); ++i) {
    const uint64_t key = pairs_[i].key;
    if (i == 0 || key != last) {
      if (leaf_.empty() || key > leaf_.back()) {
        WEAVER_RETURN_IF_ERROR(nodes.leaf_keys(key, &leaf_, &leaf_rank_));
        pos = leaf_.begin();
      }
      pos = std::lower_bound(pos, leaf_.end(), key);
      if (pos == leaf_.end() || *pos != key) {
        const Coord c = morton_decode(key);
        return Status::Corruption("node (" + std::to_string(c.x) + " " + std::to_string(c.y) + " " +
                                  std::to_string(c.z) +
                                  ") is missing from the node table: run 'weaver extract' again");
      }
      rank = leaf_rank_ + uint64_t(pos - leaf_.begin());
      last = key;
    }
    (*ids)[pairs_[i].slot / 8][pairs_[i].slot % 8] = rank;
  }
  return Status::Ok();
}

}  // namespace weaver
