// What is read from a node's key without decoding it, against the same
// from its coordinates: node_anchor_keys (and node_anchors, its coordinates)
// against anchors moved and sorted as coordinates on generated dangling
// nodes of every level, both kinds, every axis or pair of axes, on the
// root's far faces too; node_key_is_valid against node_is_valid.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <random>

#include "schema/node.h"
#include "schema/octant.h"

namespace weaver {
namespace {

// The reference: the axes with the fewest trailing zeros (0 counting as
// 31) found on the coordinates, the node moved h = 2^zeros either way along
// the first one (edge) or two (face), sorted by node key.
int reference_anchors(Coord n, NodeKind kind, Coord out[4]) {
  if (kind == NodeKind::kAnchored) return 0;
  const uint32_t c[3] = {n.x, n.y, n.z};
  int z[3];
  for (int a = 0; a < 3; ++a) z[a] = c[a] == 0 ? 31 : std::countr_zero(c[a]);
  const int low = std::min({z[0], z[1], z[2]});
  const uint32_t h = uint32_t{1} << low;
  int axes[2] = {0, 0}, count = 0;
  for (int a = 0; a < 3 && count < 2; ++a) {
    if (z[a] == low) axes[count++] = a;
  }
  const int corners = kind == NodeKind::kEdge ? 2 : 4;
  for (int k = 0; k < corners; ++k) {
    uint32_t p[3] = {c[0], c[1], c[2]};
    p[axes[0]] = (k & 1) ? c[axes[0]] + h : c[axes[0]] - h;
    if (kind == NodeKind::kFace) p[axes[1]] = (k & 2) ? c[axes[1]] + h : c[axes[1]] - h;
    out[k] = {p[0], p[1], p[2]};
  }
  std::sort(out, out + corners,
            [](const Coord& a, const Coord& b) { return node_key(a) < node_key(b); });
  return corners;
}

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
        Coord anchors[4], coords[4];
        const int n = reference_anchors(c, kind, anchors);
        uint64_t keys[4];
        ASSERT_EQ(node_anchor_keys(node_key(c), kind, keys), n);
        ASSERT_EQ(node_anchors(c, kind, coords), n);
        for (int i = 0; i < n; ++i) {
          ASSERT_EQ(node_key(coords[i]), node_key(anchors[i]));
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
