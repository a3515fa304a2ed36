// NodeClassifier against the reference mesh on every configuration of the 8
// level-1 cells around the root's centre, each absent (outside the domain),
// one leaf, or split into 8 level-2 leaves: 3^8 - 1 octrees, all 2:1
// balanced.  Every node of each, the centre and every node on the faces and
// edges where the 8 cells meet, sees its own configuration of the 8 cells
// around it (absent, a leaf it is a corner of, or a coarser leaf it lies on
// the edge or face of), so this covers every case the classifier tells
// apart, with and without the active bucket's leaves searched first.
#include "extract/node_classifier.h"

#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <vector>

#include "reference/reference_mesh.h"
#include "storage/btree.h"
#include "storage/file.h"
#include "test_util.h"

namespace weaver {
namespace {

std::vector<Octant> octree_of(int config) {
  std::vector<Octant> leaves;
  for (int cell = 0; cell < 8; ++cell, config /= 3) {
    const Octant o = octant_child(octant_root(), cell);
    if (config % 3 == 1) leaves.push_back(o);
    if (config % 3 == 2) {
      for (int c = 0; c < 8; ++c) leaves.push_back(octant_child(o, c));
    }
  }
  std::sort(leaves.begin(), leaves.end(),
            [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
  return leaves;
}

// The direction mask of every node: which of its 8 cells hold a leaf it is a corner of.
std::map<uint64_t, uint8_t> masks_of(const std::vector<Octant>& leaves) {
  std::map<uint64_t, uint8_t> masks;
  for (const Octant& o : leaves) {
    for (int k = 0; k < 8; ++k) masks[node_key(octant_corner(o, k))] |= corner_direction_bit(k);
  }
  return masks;
}

// The leaves (sorted) as a new octant table in dir, and their keys.
void write_table(testing::TempDir& dir, const std::vector<Octant>& leaves,
                 std::unique_ptr<BTree>* table, std::vector<uint64_t>* keys) {
  std::unique_ptr<File> f;
  ASSERT_OK(open_posix_file(dir.file("octants"), OpenMode::kCreateTruncate, &f));
  ASSERT_OK(BTree::create(std::move(f), TableOptions{}, 1 << 20, table));
  keys->clear();
  for (const Octant& o : leaves) keys->push_back(octant_key(o));
  ASSERT_OK((*table)->append_batch(keys->data(), nullptr, keys->size()));
}

TEST(NodeClassifierTest, EveryConfigurationOfTheCellsAroundANodeMatchesTheReference) {
  testing::TempDir dir;
  int configs = 0, dangling = 0;
  const int step = static_cast<int>(testing::scaled(1, 7));  // sanitizers: every 7th
  for (int config = 1; config < 6561; config += step) {
    const std::vector<Octant> leaves = octree_of(config);
    std::unique_ptr<BTree> table;
    std::vector<uint64_t> keys;
    ASSERT_NO_FATAL_FAILURE(write_table(dir, leaves, &table, &keys));
    const reference::Mesh ref = reference::extract(leaves);
    const std::map<uint64_t, uint8_t> masks = masks_of(leaves);
    ASSERT_EQ(masks.size(), ref.nodes.size());
    NodeClassifier plain(*table), local(*table), all_local(*table);
    all_local.set_local(&keys, 0, UINT64_MAX);
    const int shift = 3 * (kMaxLevel - 1);  // level-1 buckets
    for (const reference::MeshNode& node : ref.nodes) {
      const uint64_t key = node_key(node.c);
      const uint64_t bucket = key >> shift << shift;
      local.set_local(&keys, bucket, bucket + (uint64_t{1} << shift));
      NodeKind a = NodeKind::kAnchored, b = NodeKind::kAnchored, c = NodeKind::kAnchored;
      ASSERT_OK(plain.classify(key, masks.at(key), &a));
      ASSERT_OK(local.classify(key, masks.at(key), &b));
      ASSERT_OK(all_local.classify(key, masks.at(key), &c));
      ASSERT_EQ(a, node.kind) << "config " << config << " node " << node.c.x << " " << node.c.y
                              << " " << node.c.z;
      ASSERT_EQ(b, node.kind) << "config " << config << " (bucket leaves first)";
      ASSERT_EQ(c, node.kind) << "config " << config << " (all leaves local)";
      dangling += node.kind != NodeKind::kAnchored;
    }
    ++configs;
  }
  EXPECT_GT(dangling, configs);  // the configurations do exercise dangling nodes
}

// The nodes dangling on a coarse leaf ask for it in many directions, far
// apart in Z-order; the leaf is searched for once, then found in the cache.
// Cell 0 of the root split, the other seven level-1 leaves: the nodes on
// cell 0's far faces dangle on the six cells that share a face or an edge
// with it, and each of those is asked for by several of them.
TEST(NodeClassifierTest, ACoarseLeafIsSearchedForOnceForAllTheNodesOnIt) {
  testing::TempDir dir;
  const int config = 2 + 3 * (1 + 3 + 9 + 27 + 81 + 243 + 729);  // cell 0 split
  const std::vector<Octant> leaves = octree_of(config);
  ASSERT_EQ(leaves.size(), 15u);
  std::unique_ptr<BTree> table;
  std::vector<uint64_t> keys;
  ASSERT_NO_FATAL_FAILURE(write_table(dir, leaves, &table, &keys));
  const reference::Mesh ref = reference::extract(leaves);
  const std::map<uint64_t, uint8_t> masks = masks_of(leaves);
  NodeClassifier plain(*table), all_local(*table);
  all_local.set_local(&keys, 0, UINT64_MAX);
  int dangling = 0;
  for (const reference::MeshNode& node : ref.nodes) {
    if (node.kind == NodeKind::kAnchored) continue;
    const uint64_t key = node_key(node.c);
    NodeKind a = NodeKind::kAnchored, b = NodeKind::kAnchored;
    ASSERT_OK(plain.classify(key, masks.at(key), &a));
    ASSERT_OK(all_local.classify(key, masks.at(key), &b));
    ASSERT_EQ(a, node.kind);
    ASSERT_EQ(b, node.kind);
    ++dangling;
  }
  EXPECT_GT(dangling, 6);
  EXPECT_EQ(plain.searches(), 6u);      // each coarse leaf once, from the table
  EXPECT_EQ(all_local.searches(), 1u);  // the first search cached every local leaf
}

}  // namespace
}  // namespace weaver
