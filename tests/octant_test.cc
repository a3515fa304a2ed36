#include "schema/octant.h"

#include <gtest/gtest.h>

#include <random>
#include <set>
#include <tuple>
#include <vector>

#include "reference/octant_reference.h"
#include "test_util.h"

namespace weaver {
namespace {

std::vector<Octant> all_octants_up_to(int max_level) {
  std::vector<Octant> out;
  for (int l = 0; l <= max_level; ++l) {
    const uint32_t n = 1u << l, e = octant_edge(l);
    for (uint32_t i = 0; i < n; ++i)
      for (uint32_t j = 0; j < n; ++j)
        for (uint32_t k = 0; k < n; ++k) out.push_back({i * e, j * e, k * e, uint8_t(l)});
  }
  return out;
}

Octant random_octant(std::mt19937_64& rng, int level) {
  const uint32_t mask = ~(octant_edge(level) - 1) & (kRootEdge - 1);
  return {uint32_t(rng()) & mask, uint32_t(rng()) & mask, uint32_t(rng()) & mask, uint8_t(level)};
}

void check_one(const Octant& o) {
  ASSERT_TRUE(octant_is_valid(o));
  const uint64_t key = octant_key(o);
  ASSERT_TRUE(octant_key_is_valid(key));
  ASSERT_EQ(octant_from_key(key), o);
  Octant into{1, 2, 3, 4};
  octant_decode_into(key, &into);
  ASSERT_EQ(into, o);
  ASSERT_EQ(octant_key_morton(key), reference::morton_encode(o.x, o.y, o.z));
  ASSERT_EQ(octant_key_level(key), o.level);
  ASSERT_EQ(octant_morton(o), reference::morton_encode(o.x, o.y, o.z));
  if (o.level > 0) {
    ASSERT_EQ(octant_parent(o), reference::parent(o));
    ASSERT_EQ(octant_key_parent(key), octant_key(reference::parent(o)));
    ASSERT_EQ(octant_child_id(o), reference::child_id(o));
    ASSERT_EQ(octant_key_child_id(key), reference::child_id(o));
  }
  if (o.level < kMaxLevel) {
    for (int k = 0; k < 8; ++k) {
      const Octant c = octant_child(o, k);
      ASSERT_EQ(c, reference::child(o, k));
      ASSERT_EQ(octant_key_child(key, k), octant_key(reference::child(o, k)));
      ASSERT_TRUE(octant_is_ancestor(o, c));
      ASSERT_LT(key, octant_key(c));
      ASSERT_LT(octant_key(c), octant_key_subtree_end(o));
    }
  }
  // The octants of one level inside o, in Z-order, step by the stride.
  if (o.level + 2 < kMaxLevel) {
    const uint64_t first = octant_key(reference::child(reference::child(o, 0), 0));
    for (int i = 0; i < 64; ++i) {
      const Octant g = reference::child(reference::child(o, i / 8), i % 8);
      ASSERT_EQ(octant_key(g), first + i * octant_key_stride(o.level + 2));
    }
  }
  for (const Direction d : kAllDirections) {
    Octant fast{}, slow{};
    const bool in_fast = octant_neighbour(o, d, &fast);
    ASSERT_EQ(in_fast, reference::neighbour(o, d.dx, d.dy, d.dz, &slow));
    if (in_fast) {
      ASSERT_EQ(fast, slow);
    }
    if (o.level < kMaxLevel) {
      uint64_t by_key = 0, by_parts = 1;
      ASSERT_EQ(octant_key_neighbour(key, d, &by_key), in_fast);
      ASSERT_EQ(KeyNeighbours(key).neighbour(d, &by_parts), in_fast);
      if (in_fast) {
        ASSERT_EQ(by_key, octant_key(slow));
        ASSERT_EQ(by_parts, octant_key(slow));
      } else {
        ASSERT_EQ(by_parts, 0u);
      }
    }
  }
  for (int k = 0; k < 8; ++k) {
    const Coord c = octant_corner(o, k);
    const uint64_t e = reference::edge(o.level);
    ASSERT_EQ(c.x, o.x + (k & 1) * e);
    ASSERT_EQ(c.y, o.y + ((k >> 1) & 1) * e);
    ASSERT_EQ(c.z, o.z + ((k >> 2) & 1) * e);
    ASSERT_TRUE(node_is_valid(c));
    ASSERT_EQ(octant_contains_point(o, c), k == 0);
  }
}

void check_pair(const Octant& a, const Octant& b) {
  ASSERT_EQ(octant_key(a) < octant_key(b), reference::key_less(a, b));
  ASSERT_EQ(octant_is_ancestor(a, b), reference::is_ancestor(a, b));
  ASSERT_EQ(octant_nearest_common_ancestor(a, b), reference::nearest_common_ancestor(a, b));
}

TEST(Octant, SingleOctantOperationsMatchReferenceUpToLevel4) {
  for (const Octant& o : all_octants_up_to(4)) ASSERT_NO_FATAL_FAILURE(check_one(o));
}

TEST(Octant, PairOperationsMatchReferenceExhaustivelyUpToLevel4) {
  const std::vector<Octant> all = all_octants_up_to(testing::small_scale() ? 3 : 4);
  for (const Octant& a : all) {
    const uint64_t ka = octant_key(a);
    const uint64_t ma = reference::morton_encode(a.x, a.y, a.z);
    for (const Octant& b : all) {
      const uint64_t mb = reference::morton_encode(b.x, b.y, b.z);
      const bool ref_less = ma < mb || (ma == mb && a.level < b.level);
      ASSERT_EQ(ka < octant_key(b), ref_less);
      ASSERT_EQ(octant_is_ancestor(a, b), reference::is_ancestor(a, b));
    }
  }
  const std::vector<Octant> small = all_octants_up_to(3);
  for (const Octant& a : small)
    for (const Octant& b : small) ASSERT_NO_FATAL_FAILURE(check_pair(a, b));
}

TEST(Octant, RandomOctantsAtEveryLevelMatchReference) {
  std::mt19937_64 rng(7);
  const uint64_t per_level = testing::scaled(100'000, 5'000);
  for (int level = 0; level <= kMaxLevel; ++level) {
    for (uint64_t i = 0; i < per_level; ++i) {
      const Octant o = random_octant(rng, level);
      ASSERT_NO_FATAL_FAILURE(check_one(o));
      // A random octant, and one related to o (an ancestor's descendant), so
      // that ancestry and common ancestors are exercised, not just disjoint pairs.
      const Octant other = random_octant(rng, rng() % (kMaxLevel + 1));
      ASSERT_NO_FATAL_FAILURE(check_pair(o, other));
      const int up = static_cast<int>(rng() % (level + 1));
      Octant related = octant_ancestor(o, up);
      const int down = static_cast<int>(rng() % (kMaxLevel - up + 1));
      for (int d = 0; d < down; ++d) related = octant_child(related, static_cast<int>(rng() % 8));
      ASSERT_NO_FATAL_FAILURE(check_pair(o, related));
      ASSERT_NO_FATAL_FAILURE(check_pair(related, o));
      const Coord p{uint32_t(rng()) & (kRootEdge - 1), uint32_t(rng()) & (kRootEdge - 1),
                    uint32_t(rng()) & (kRootEdge - 1)};
      const Coord q{o.x + uint32_t(rng() % (2 * octant_edge(o))), o.y, o.z};
      ASSERT_EQ(octant_contains_point(o, p), reference::contains_point(o, p.x, p.y, p.z));
      ASSERT_EQ(octant_contains_point(o, q), reference::contains_point(o, q.x, q.y, q.z));
    }
  }
}

TEST(Octant, PixelKeyFloorIsTheContainingLeafInPreorder) {
  // Keys of a leaf set sort in preorder, and the largest leaf key <= the
  // pixel key of p is the leaf containing p.
  std::mt19937_64 rng(3);
  std::vector<Octant> leaves = {octant_root()};
  for (int step = 0; step < 200; ++step) {
    const size_t i = rng() % leaves.size();
    if (leaves[i].level >= kMaxLevel) continue;
    const Octant o = leaves[i];
    leaves.erase(leaves.begin() + static_cast<long>(i));
    for (int k = 0; k < 8; ++k) leaves.push_back(octant_child(o, k));
  }
  std::vector<uint64_t> keys;
  for (const Octant& o : leaves) keys.push_back(octant_key(o));
  std::sort(keys.begin(), keys.end());
  for (int t = 0; t < 20000; ++t) {
    const Coord p{uint32_t(rng()) & (kRootEdge - 1), uint32_t(rng()) & (kRootEdge - 1),
                  uint32_t(rng()) & (kRootEdge - 1)};
    auto it = std::upper_bound(keys.begin(), keys.end(), pixel_key(p));
    ASSERT_NE(it, keys.begin());
    ASSERT_TRUE(octant_contains_point(octant_from_key(*(it - 1)), p));
  }
}

TEST(Octant, KeyValidityRejectsMisalignedAndBadSlots) {
  EXPECT_TRUE(octant_key_is_valid(octant_key({0, 0, 0, 0})));
  EXPECT_FALSE(octant_key_is_valid(28));             // slot 28 is unused
  EXPECT_FALSE(octant_key_is_valid((8 >> 3) << 7));  // Morton 8 at level 0: misaligned
  EXPECT_EQ(octant_key_subtree_end(octant_root()), UINT64_MAX);
  EXPECT_FALSE(octant_is_valid({1, 0, 0, 19}));
  EXPECT_FALSE(octant_is_valid({kRootEdge, 0, 0, 20}));
  EXPECT_TRUE(node_is_valid({kRootEdge, kRootEdge, kRootEdge}));
  EXPECT_FALSE(pixel_is_valid({kRootEdge, 0, 0}));
}

}  // namespace
}  // namespace weaver

namespace weaver {
namespace {

// The direction tables hold each of the 26 directions once, by kind.
TEST(OctantTest, DirectionTablesHoldEveryDirectionOnceByKind) {
  std::set<std::tuple<int, int, int>> seen;
  auto check = [&](const auto& table, Direction::Kind kind) {
    for (const Direction d : table) {
      EXPECT_TRUE(d.is_valid());
      EXPECT_EQ(d.kind(), kind);
      EXPECT_TRUE(seen.insert({d.dx, d.dy, d.dz}).second);
    }
  };
  check(kFaceDirections, Direction::Kind::kFace);
  check(kEdgeDirections, Direction::Kind::kEdge);
  check(kCornerDirections, Direction::Kind::kCorner);
  EXPECT_EQ(seen.size(), 26u);
  std::set<std::tuple<int, int, int>> all, face_edge;
  for (const Direction d : kAllDirections) all.insert({d.dx, d.dy, d.dz});
  for (const Direction d : kFaceAndEdgeDirections) face_edge.insert({d.dx, d.dy, d.dz});
  EXPECT_EQ(all, seen);
  EXPECT_EQ(face_edge.size(), 18u);
  for (const auto& [dx, dy, dz] : face_edge) EXPECT_LT((dx != 0) + (dy != 0) + (dz != 0), 3);
  EXPECT_FALSE((Direction{0, 0, 0}.is_valid()));
  EXPECT_FALSE((Direction{2, 0, 0}.is_valid()));
}

}  // namespace
}  // namespace weaver
