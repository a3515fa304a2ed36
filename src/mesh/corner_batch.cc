#include "mesh/corner_batch.h"

#include <algorithm>
#include <string>

#include "schema/node.h"
#include "util/radix_sort.h"

namespace weaver {

Status CornerBatch::resolve(BTree& nodes, const std::vector<Octant>& elements,
                            std::vector<std::array<uint64_t, 8>>* ids) {
  pairs_.clear();
  for (size_t i = 0; i < elements.size(); ++i) {
    for (int k = 0; k < 8; ++k)
      pairs_.push_back({node_key(octant_corner(elements[i], k)), 8 * i + k});
  }
  radix_sort_by(pairs_, scratch_, [](const KeySlot& p) { return p.key; });
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
