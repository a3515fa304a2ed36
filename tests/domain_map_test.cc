// balance's domain map against the leaves themselves: for octrees with
// holes and non-cube domains, at every map level, each octant near the
// leaves is answered as a brute-force search over the leaves answers it,
// and left to the leaves only where the map's cell is covered in part.
#include "balance/domain_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "gen/octree_gen.h"
#include "schema/octant.h"
#include "test_util.h"

namespace weaver {
namespace {

bool overlap(const Octant& a, const Octant& b) {
  return octant_is_ancestor(a, b) || octant_is_ancestor(b, a) || a == b;
}

bool any_leaf_overlaps(const std::vector<Octant>& leaves, const Octant& o) {
  return std::any_of(leaves.begin(), leaves.end(), [&](const Octant& q) { return overlap(q, o); });
}

// Whether the leaves cover all of o.
bool leaves_cover(const std::vector<Octant>& leaves, const Octant& o) {
  uint64_t volume = 0;
  for (const Octant& q : leaves) {
    if (octant_is_ancestor(q, o) || q == o) return true;
    if (octant_is_ancestor(o, q)) volume += uint64_t{1} << (3 * (kMaxLevel - q.level));
  }
  return volume == uint64_t{1} << (3 * (kMaxLevel - o.level));
}

// Octants around the leaves: their ancestors, some children and
// grandchildren, and the neighbours of all of these (many outside).
std::vector<Octant> octants_near(const std::vector<Octant>& leaves, std::mt19937_64& rng) {
  std::vector<Octant> near;
  for (int i = 0; i < 60; ++i) {
    const Octant q = leaves[rng() % leaves.size()];
    near.push_back(octant_ancestor(q, static_cast<int>(rng() % (q.level + 1))));
    Octant d = q;
    for (int down = 0; down < 2 && d.level < kMaxLevel; ++down) {
      d = octant_child(d, static_cast<int>(rng() % 8));
      near.push_back(d);
    }
  }
  const size_t base = near.size();
  for (size_t i = 0; i < base; ++i) {
    for (const Direction& dir : kAllDirections) {
      Octant n;
      if (octant_neighbour(near[i], dir, &n)) near.push_back(n);
    }
  }
  return near;
}

TEST(DomainMap, AnswersAsTheLeavesDoAtEveryLevel) {
  std::mt19937_64 rng(17);
  int asked = 0, holes = 0, covered = 0;
  for (int t = 0; t < static_cast<int>(testing::scaled(60, 15)); ++t) {
    GenOptions g;
    g.seed = rng();
    g.block_level = static_cast<int>(rng() % 3);
    for (int a = 0; a < 3; ++a) g.blocks[a] = 1 + rng() % (1u << g.block_level);
    g.leaves = 20 + rng() % 300;
    g.max_level = g.block_level + 1 + static_cast<int>(rng() % 7);
    std::vector<Octant> all, leaves;
    ASSERT_OK(generate_octree(g, &all));
    // Holes: a leaf in five is left out.
    for (const Octant& q : all) {
      if (rng() % 5 != 0) leaves.push_back(q);
    }
    if (leaves.empty()) continue;
    holes += leaves.size() < all.size();
    std::sort(leaves.begin(), leaves.end(),
              [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
    const std::vector<Octant> near = octants_near(leaves, rng);
    for (int level = 0; level <= std::min(g.max_level + 1, 9); ++level) {
      SCOPED_TRACE("case " + std::to_string(t) + ", map level " + std::to_string(level));
      DomainMap map(level);
      // Written as two stretches cut where the map allows near the median
      // leaf, as balance's first scan does (one when the cut is the start).
      const uint64_t cut = map.stretch_start(octant_key(leaves[leaves.size() / 2]));
      DomainMap::Writer before(&map), after(&map);
      for (const Octant& q : leaves) (octant_key(q) < cut ? before : after).add_leaf(octant_key(q));
      before.finish();
      after.finish();
      for (const Octant& o : near) {
        const bool want = any_leaf_overlaps(leaves, o);
        const DomainMap::Answer a = map.overlaps(octant_key(o));
        if (a == DomainMap::Answer::kAskTheLeaves) {
          ++asked;
          // Only an octant at or below the map's level, in a cell the
          // leaves cover in part.
          ASSERT_GE(o.level, level);
          const Octant cell = octant_ancestor(o, level);
          ASSERT_TRUE(any_leaf_overlaps(leaves, cell));
          ASSERT_FALSE(leaves_cover(leaves, cell));
        } else {
          ASSERT_EQ(a == DomainMap::Answer::kYes, want)
              << "(" << o.x << " " << o.y << " " << o.z << " " << int(o.level) << ")";
        }
        // covers: never wrongly; always for an octant in a covered cell.
        if (map.covers(octant_key(o))) {
          ASSERT_TRUE(leaves_cover(leaves, o));
          ++covered;
        } else if (o.level >= level) {
          ASSERT_FALSE(leaves_cover(leaves, octant_ancestor(o, level)));
        }
      }
    }
  }
  EXPECT_GT(holes, 0);
  EXPECT_GT(asked, 0);  // some cells are covered in part
  EXPECT_GT(covered, 0);
}

TEST(DomainMap, LevelFitsTheBytesAndStopsAtTheFinestLeaves) {
  EXPECT_EQ(DomainMap::level_for(0, 20), 0);
  EXPECT_EQ(DomainMap::level_for(2, 20), 1);   // 8 cells * 2 bits
  EXPECT_EQ(DomainMap::level_for(15, 20), 1);  // level 2 takes 16 bytes
  EXPECT_EQ(DomainMap::level_for(16, 20), 2);
  EXPECT_EQ(DomainMap::level_for(4u << 20, 20), 8);   // 2^24 cells * 2 bits = 4 MiB
  EXPECT_EQ(DomainMap::level_for(32u << 20, 20), 9);  // 32 MiB
  EXPECT_EQ(DomainMap::level_for(32u << 20, 5), 5);
}

}  // namespace
}  // namespace weaver
