// locate and range queries against brute force over the leaf list.
#include <gtest/gtest.h>

#include <random>

#include "db/database.h"
#include "gen/octree_gen.h"
#include "import/import.h"
#include "import/octant_text.h"
#include "mesh/octant_query.h"
#include "test_util.h"

namespace weaver {
namespace {

class QueryTest : public ::testing::Test {
 protected:
  // Generates, writes shuffled, imports, and opens the octant table.
  void build(const GenOptions& g) {
    ASSERT_OK(generate_octree(g, &leaves_));
    const std::string text = dir_.file("octants.txt");
    ASSERT_OK(write_octant_text(text, leaves_, "test"));
    ImportOptions o;
    o.memory = MemoryBudget(64 << 20);
    ImportResult r;
    ASSERT_OK(import_octants(dir_.file("db"), text, o, &r));
    ASSERT_OK(Database::open(dir_.file("db"), Database::Mode::kRead, false, &db_));
    ASSERT_OK(db_->open_table(kOctantTable, 64 << 20, &table_));
    std::sort(leaves_.begin(), leaves_.end(),
              [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
  }

  Coord random_pixel(std::mt19937_64& rng) {
    return {uint32_t(rng() % kRootEdge), uint32_t(rng() % kRootEdge), uint32_t(rng() % kRootEdge)};
  }

  void check_locate(Coord p) {
    LocateResult r;
    ASSERT_OK(locate(*table_, p, &r));
    int64_t expected = -1;  // brute force: the one leaf whose box holds p
    for (size_t i = 0; i < leaves_.size(); ++i) {
      const Octant& o = leaves_[i];
      const uint32_t e = octant_edge(o);
      if (o.x <= p.x && p.x < o.x + e && o.y <= p.y && p.y < o.y + e && o.z <= p.z &&
          p.z < o.z + e) {
        ASSERT_EQ(expected, -1) << "leaves overlap";
        expected = static_cast<int64_t>(i);
      }
    }
    ASSERT_EQ(r.inside, expected >= 0) << p.x << " " << p.y << " " << p.z;
    if (r.inside) {
      EXPECT_EQ(r.leaf, leaves_[expected]);
      EXPECT_EQ(r.element_id, static_cast<uint64_t>(expected));
    }
  }

  testing::TempDir dir_;
  std::vector<Octant> leaves_;
  std::unique_ptr<Database> db_;
  std::unique_ptr<BTree> table_;
};

TEST_F(QueryTest, LocateMatchesBruteForceOnAMillionLeafShuffledImport) {
  GenOptions g;
  g.leaves = testing::scaled(1'000'000, 150'000);
  g.blocks[0] = 4, g.blocks[1] = 4, g.blocks[2] = 3;  // non-cube: points outside exist
  g.block_level = 2;
  g.shuffle = true;
  g.seed = 5;
  ASSERT_NO_FATAL_FAILURE(build(g));
  ASSERT_GE(leaves_.size(), g.leaves);
  std::mt19937_64 rng(17);
  const int points = static_cast<int>(testing::scaled(2000, 300));
  for (int i = 0; i < points; ++i) ASSERT_NO_FATAL_FAILURE(check_locate(random_pixel(rng)));
  // Points at leaf corners and just before the far faces: the boundary cases.
  for (int i = 0; i < points; ++i) {
    const Octant& o = leaves_[rng() % leaves_.size()];
    const uint32_t e = octant_edge(o);
    ASSERT_NO_FATAL_FAILURE(check_locate({o.x, o.y, o.z}));
    ASSERT_NO_FATAL_FAILURE(check_locate({o.x + e - 1, o.y + e - 1, o.z + e - 1}));
  }
}

TEST_F(QueryTest, LocateRejectsPointsOutsideTheAddressSpace) {
  GenOptions g;
  g.leaves = 100;
  ASSERT_NO_FATAL_FAILURE(build(g));
  LocateResult r;
  EXPECT_TRUE(locate(*table_, {kRootEdge, 0, 0}, &r).is_invalid_argument());
}

TEST_F(QueryTest, RangeMatchesBruteForce) {
  GenOptions g;
  g.leaves = 20'000;
  g.blocks[0] = 3, g.blocks[1] = 4, g.blocks[2] = 2;
  g.block_level = 2;
  g.seed = 9;
  ASSERT_NO_FATAL_FAILURE(build(g));
  std::mt19937_64 rng(23);
  for (int t = 0; t < 300; ++t) {
    Coord a = random_pixel(rng), b = random_pixel(rng);
    if (t % 3 == 0) {  // small boxes too
      b = {std::min(a.x + uint32_t(rng() % 5000), kRootEdge - 1),
           std::min(a.y + uint32_t(rng() % 5000), kRootEdge - 1),
           std::min(a.z + uint32_t(rng() % 5000), kRootEdge - 1)};
    }
    const TickBox box{{std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)},
                      {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}};
    std::vector<uint64_t> expected;
    for (size_t i = 0; i < leaves_.size(); ++i) {
      const Octant& o = leaves_[i];
      const uint64_t e = octant_edge(o);
      if (o.x <= box.hi.x && o.x + e > box.lo.x && o.y <= box.hi.y && o.y + e > box.lo.y &&
          o.z <= box.hi.z && o.z + e > box.lo.z) {
        expected.push_back(i);
      }
    }
    uint64_t count = 0;
    std::vector<uint64_t> got;
    ASSERT_OK(range_query(*table_, box, &count, [&](const Octant& o, uint64_t id) {
      EXPECT_EQ(o, leaves_[id]);
      got.push_back(id);
    }));
    ASSERT_EQ(got, expected);
    uint64_t count_only = 0;
    ASSERT_OK(range_query(*table_, box, &count_only, nullptr));
    ASSERT_EQ(count_only, expected.size());
    ASSERT_EQ(count, expected.size());
  }
  uint64_t count = 0;
  EXPECT_TRUE(range_query(*table_, {{5, 0, 0}, {4, 9, 9}}, &count, nullptr).is_invalid_argument());
}

}  // namespace
}  // namespace weaver
