#include "extract/ghost_layer.h"

#include <algorithm>

#include "db/octant_table.h"
#include "extract/bucket_worker.h"
#include "schema/octant.h"
#include "util/octant_key_stream.h"

namespace weaver {
namespace {

// Adds key to the lists of ranks [from, to] other than `rank` (each list
// once: a leaf meets a rank through several neighbours).
void send_to(uint64_t key, size_t from, size_t to, const std::vector<uint64_t>& start, int rank,
             std::vector<std::vector<uint64_t>>* outgoing) {
  for (size_t s = from; s <= to; ++s) {
    std::vector<uint64_t>& list = (*outgoing)[s];
    if (static_cast<int>(s) == rank || start[s] == start[s + 1]) continue;
    if (list.empty() || list.back() != key) list.push_back(key);
  }
}

}  // namespace

Status ghost_leaves(BTree& octants, uint64_t first_leaf, uint64_t stop,
                    const std::vector<uint64_t>& start, int rank,
                    std::vector<std::vector<uint64_t>>* outgoing) {
  outgoing->assign(start.size() - 1, {});  // start has an entry for the end
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(octants.seek_keys(first_leaf, &c));
  for (; c.valid() && octant_key_morton(c.key()) < stop;) {
    const uint64_t key = c.key();
    WEAVER_RETURN_IF_ERROR(c.next());
    const int bit = kMaxLevel - octant_key_level(key);
    const uint64_t m = octant_key_morton(key), span = uint64_t{1} << (3 * bit);
    // The far corner has the largest code of the leaf's closure: below
    // stop, the whole closure is this rank's.
    if (morton_step(morton_step(morton_step(m, 0, bit), 1, bit), 2, bit) < stop) continue;
    for (int d = 1; d < 8; ++d) {  // the neighbours on the + side of the axes in d
      uint64_t box = m;
      for (int a = 0; a < 3; ++a) {
        if ((d >> a) & 1) box = morton_step(box, a, bit);
      }
      if (box + span - 1 < stop) continue;
      send_to(key, rank_holding(start, box), rank_holding(start, box + span - 1), start, rank,
              outgoing);
    }
  }
  return Status::Ok();
}

Status spill_ghost_corners(const std::vector<uint64_t>& ghosts, uint64_t start, uint64_t stop,
                           SpillStore& spills) {
  constexpr size_t kGhostsARun = size_t{1} << 15;  // 256K records at most, 4 MB
  SpillRun run;
  uint64_t corners[8];
  for (size_t from = 0; from < ghosts.size(); from += kGhostsARun) {
    run.begin(start, stop - 1);
    for (size_t i = from; i < std::min(ghosts.size(), from + kGhostsARun); ++i) {
      leaf_corner_keys(ghosts[i], corners);
      for (int k = 0; k < 8; ++k) {
        if (corners[k] >= start && corners[k] < stop) run.add(corners[k], corner_direction_bit(k));
      }
    }
    WEAVER_RETURN_IF_ERROR(run.flush(spills));
  }
  return Status::Ok();
}

}  // namespace weaver
