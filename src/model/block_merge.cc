#include "model/block_merge.h"

#include <cassert>

namespace weaver {

BlockMerger::BlockMerger(int levels) : levels_(levels) {
  assert(levels >= 1 && levels <= 7);
  const uint64_t cells = uint64_t{1} << (3 * levels);
  values_.resize(cells);
  present_.resize(cells);
  for (int d = 0; d < levels; ++d) {
    whole_.emplace_back(uint64_t{1} << (3 * d));
    nodes_.emplace_back(uint64_t{1} << (3 * d));
  }
}

Status BlockMerger::merge_into(const Octant& block, MaterialMerger& merger) {
  MaterialMerger::Entry eight[8];
  for (int d = levels_ - 1; d >= 0; --d) {
    const bool finest = d + 1 == levels_;
    const uint64_t count = uint64_t{1} << (3 * d);
    for (uint64_t n = 0; n < count; ++n) {
      bool all = true;
      for (int c = 0; c < 8 && all; ++c) {
        const uint64_t child = 8 * n + c;
        if (finest) {
          all = present_[child] != 0;
          const ModelValues& v = values_[child];
          eight[c].mean = eight[c].low = eight[c].high = v;
        } else {
          all = whole_[d + 1][child] != 0;
          eight[c] = nodes_[d + 1][child];
        }
      }
      whole_[d][n] = all && merger.agree(eight);
      if (whole_[d][n]) nodes_[d][n] = merger.merged(Octant{}, eight);
    }
  }
  return emit(block, 0, 0, merger);
}

// The node `index` at `depth` below the block's root, which is octant o:
// one entry when it merged, else its children's, in key order.
Status BlockMerger::emit(const Octant& o, int depth, uint64_t index, MaterialMerger& merger) const {
  if (depth == levels_) return present_[index] ? merger.add(o, values_[index]) : Status::Ok();
  if (whole_[depth][index]) {
    MaterialMerger::Entry e = nodes_[depth][index];
    e.octant = o;
    return merger.add(e);
  }
  for (int c = 0; c < 8; ++c) {
    WEAVER_RETURN_IF_ERROR(emit(octant_child(o, c), depth + 1, 8 * index + c, merger));
  }
  return Status::Ok();
}

}  // namespace weaver
