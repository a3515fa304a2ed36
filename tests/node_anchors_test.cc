// node_anchor_keys (from a node's key, no decoding) against node_anchors
// (from its coordinates) on generated dangling nodes of every level, both
// kinds, every axis or pair of axes, on the root's far faces too.
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

}  // namespace
}  // namespace weaver
