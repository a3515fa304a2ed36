// What is read from a node's key without decoding it, against the same
// from its coordinates: node_anchor_keys against node_anchors on generated
// dangling nodes of every level, both kinds, every axis or pair of axes, on
// the root's far faces too; node_key_is_valid against node_is_valid.
#include <gtest/gtest.h>

#include <random>

#include "schema/node.h"
#include "schema/octant.h"

namespace weaver {
namespace {

// A coordinate that is an odd multiple of h (inside) or a multiple of 2h
// (on the coarse leaf's lattice, 0 and the root's far side included).
uint32_t coordinate(std::mt19937_64& rng, uint32_t h, bool odd) {
  const uint32_t steps = kRootEdge / (2 * h);
  if (odd) return static_cast<uint32_t>(2 * (rng() % steps) + 1) * h;
  return static_cast<uint32_t>(rng() % (steps + 1)) * 2 * h;
}

TEST(NodeAnchors, KeysFromTheNodeKeyAreThoseOfItsCoordinates) {
  std::mt19937_64 rng(51);
  int cases = 0;
  for (int level = 1; level <= kMaxLevel; ++level) {  // the fine leaves' level
    const uint32_t h = octant_edge(level);
    for (int axes = 1; axes < 7; ++axes) {  // the inside axes: 1 (edge) or 2 (face)
      const int inside = std::popcount(static_cast<unsigned>(axes));
      if (inside == 3) continue;
      const NodeKind kind = inside == 1 ? NodeKind::kEdge : NodeKind::kFace;
      for (int r = 0; r < 40; ++r) {
        const Coord c{coordinate(rng, h, axes & 1), coordinate(rng, h, axes & 2),
                      coordinate(rng, h, axes & 4)};
        Coord anchors[4];
        const int n = node_anchors(c, kind, anchors);
        uint64_t keys[4];
        ASSERT_EQ(node_anchor_keys(node_key(c), kind, keys), n);
        for (int i = 0; i < n; ++i) {
          ASSERT_EQ(keys[i], node_key(anchors[i])) << "node " << c.x << " " << c.y << " " << c.z
                                                   << " level " << level << " anchor " << i;
        }
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, kMaxLevel * 6 * 40);
  uint64_t keys[4];
  EXPECT_EQ(node_anchor_keys(node_key({4, 8, 12}), NodeKind::kAnchored, keys), 0);
}

TEST(NodeKeys, ValidWithoutDecodingExactlyWhenTheCoordinatesAre) {
  std::mt19937_64 rng(20);
  const uint32_t edge = kRootEdge;
  const uint32_t near[] = {0,        1,           edge / 2, edge - 1, edge, edge + 1, 2 * edge - 1,
                           2 * edge, 4 * edge - 1};
  int valid = 0, invalid = 0;
  auto check = [&](uint64_t key) {
    // morton_decode keeps 21 bits an axis: key bit 63 (x's bit 21) is
    // refused apart, as no node's key has it.
    const bool expected = (key >> 63) == 0 && node_is_valid(morton_decode(key));
    ASSERT_EQ(node_key_is_valid(key), expected) << "key " << key;
    (expected ? valid : invalid) += 1;
  };
  for (uint32_t x : near)
    for (uint32_t y : near)
      for (uint32_t z : near) {
        if (x < 2 * edge && y < 2 * edge && z < 2 * edge) check(morton_encode({x, y, z}));
      }
  for (int i = 0; i < 100000; ++i) check(rng() >> (rng() % 8));
  EXPECT_GT(valid, 1000);
  EXPECT_GT(invalid, 1000);
}

}  // namespace
}  // namespace weaver
