// The ghost layer of a parallel extract (extract/ghost_layer.h), against a
// reference that looks at every pair of leaf and node: every leaf of an
// earlier rank that has one of rank r's nodes on its closure (corner, edge
// or face) must reach r, since r's classifier looks for it; and the
// corners the ghosts give r are exactly those in r's range.
#include "extract/ghost_layer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <vector>

#include "balance/balance.h"
#include "db/database.h"
#include "db/octant_table.h"
#include "extract/bucket_worker.h"
#include "sample_octrees.h"
#include "test_util.h"

namespace weaver {
namespace {

using testing::TempDir;

// Whether node n lies on the closure of octant o.
bool on_closure(Coord n, const Octant& o) {
  const uint64_t e = octant_edge(o);
  const uint64_t c[3] = {n.x, n.y, n.z}, lo[3] = {o.x, o.y, o.z};
  for (int a = 0; a < 3; ++a) {
    if (c[a] < lo[a] || c[a] > lo[a] + e) return false;
  }
  return true;
}

// The rank whose node keys hold key (start as cut_equal_runs gives it).
size_t owner(const std::vector<uint64_t>& start, uint64_t key) {
  return std::upper_bound(start.begin(), start.end(), key) - start.begin() - 1;
}

// For each leaf (in key order), the nodes on its closure: every leaf corner
// there.
std::vector<std::vector<uint64_t>> nodes_on_leaves(const std::vector<uint64_t>& keys) {
  std::set<uint64_t> nodes;
  uint64_t corners[8];
  for (uint64_t k : keys) {
    leaf_corner_keys(k, corners);
    nodes.insert(corners, corners + 8);
  }
  std::vector<std::vector<uint64_t>> on(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    const Octant o = octant_from_key(keys[i]);
    for (uint64_t n : nodes) {
      if (on_closure(morton_decode(n), o)) on[i].push_back(n);
    }
  }
  return on;
}

// For each rank, the leaves of other ranks that some node it owns lies on:
// what its classifier may look up.
std::vector<std::set<uint64_t>> reference_ghosts(const std::vector<uint64_t>& keys,
                                                 const std::vector<std::vector<uint64_t>>& on,
                                                 const std::vector<uint64_t>& start) {
  std::vector<std::set<uint64_t>> want(start.size() - 1);
  for (size_t i = 0; i < keys.size(); ++i) {
    const size_t mine = owner(start, octant_key_morton(keys[i]));
    for (uint64_t n : on[i]) {
      if (owner(start, n) != mine) want[owner(start, n)].insert(keys[i]);
    }
  }
  return want;
}

TEST(GhostLayer, EveryLeafAroundARanksNodesReachesIt) {
  TempDir dir;
  std::vector<std::string> octrees = {testing::two_family_octree(dir, "families")};
  for (uint64_t seed : {11, 12, 13}) {
    octrees.push_back(testing::random_octree(dir, "random" + std::to_string(seed), seed,
                                             5 + 2 * seed % 7, seed == 12, 1500));
  }
  // Balanced too: the layer extract actually sees.
  const std::string balanced = testing::random_octree(dir, "balanced", 14, 9, true, 1500);
  BalanceResult br;
  ASSERT_OK(balance_octree(balanced, BalanceOptions{}, &br));
  octrees.push_back(balanced);
  for (size_t i = 0; i < octrees.size(); ++i) {
    std::unique_ptr<Database> d;
    ASSERT_OK(Database::open(octrees[i], Database::Mode::kRead, false, &d));
    std::unique_ptr<BTree> t;
    ASSERT_OK(d->open_table(kOctantTable, 1 << 20, &t));
    const std::vector<uint64_t> keys = testing::octant_table_keys(octrees[i]);
    const std::vector<std::vector<uint64_t>> on = nodes_on_leaves(keys);
    for (int ranks : {1, 2, 3, 5, 8, 13}) {
      SCOPED_TRACE("octree " + std::to_string(i) + " on " + std::to_string(ranks) + " ranks");
      std::vector<uint64_t> first, start;
      ASSERT_OK(cut_equal_runs(*t, ranks, &first, &start));
      const std::vector<std::set<uint64_t>> want = reference_ghosts(keys, on, start);
      std::vector<std::vector<uint64_t>> got(ranks);  // [to]
      for (int q = 0; q < ranks; ++q) {
        if (start[q] >= start[q + 1]) continue;
        std::vector<std::vector<uint64_t>> out;
        ASSERT_OK(ghost_leaves(*t, first[q], start[q + 1], start, q, &out));
        ASSERT_EQ(out.size(), size_t(ranks));
        for (int r = 0; r < ranks; ++r) {
          if (r <= q) {
            EXPECT_TRUE(out[r].empty()) << "rank " << q << " sent back to " << r;
          }
          EXPECT_TRUE(std::is_sorted(out[r].begin(), out[r].end()));
          got[r].insert(got[r].end(), out[r].begin(), out[r].end());
        }
      }
      for (int r = 0; r < ranks; ++r) {
        const std::set<uint64_t> have(got[r].begin(), got[r].end());
        EXPECT_EQ(have.size(), got[r].size()) << "a ghost sent twice to rank " << r;
        for (uint64_t k : want[r]) {
          EXPECT_TRUE(have.count(k))
              << "rank " << r << " lacks " << describe_octant(octant_from_key(k));
        }
        // The corners the ghosts give: those in r's range, with the bits of
        // every ghost that has them as a corner.
        SpillStore spills(dir.file("spills"), 1 << 16);  // small: some go to disk
        ASSERT_OK(spill_ghost_corners(got[r], start[r], start[r + 1], spills));
        std::vector<SpillRecord> records;
        ASSERT_OK(spills.take_below(UINT64_MAX, &records));
        std::map<uint64_t, uint8_t> have_masks, masks;
        for (const SpillRecord& rec : records) have_masks[rec.key] |= rec.mask;
        uint64_t corners[8];
        for (uint64_t k : got[r]) {
          leaf_corner_keys(k, corners);
          for (int c = 0; c < 8; ++c) {
            if (owner(start, corners[c]) == size_t(r)) masks[corners[c]] |= corner_direction_bit(c);
          }
        }
        EXPECT_TRUE(have_masks == masks);
      }
    }
  }
}

}  // namespace
}  // namespace weaver
