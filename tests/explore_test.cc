// The Explorer (query/explorer.h) against brute force: neighbours across
// faces, edges and corners, the elements around a node, the nodes that
// depend on a node, and batches of points answered in input order.
#include <gtest/gtest.h>

#include <random>

#include "gen/octree_gen.h"
#include "import/import.h"
#include "import/octant_text.h"
#include "query/explorer.h"
#include "query/shared_batch.h"
#include "reference/reference_mesh.h"
#include "test_mesh.h"
#include "test_octrees.h"
#include "test_util.h"

namespace weaver {
namespace {

// Random refinements of non-cube block domains, and of the root with holes
// as fine as the leaves: unbalanced (steps of several levels) when
// `balanced` is false.
std::vector<std::vector<Octant>> octrees(bool balanced, uint64_t leaves) {
  std::vector<std::vector<Octant>> out;
  for (uint64_t seed = 1; seed <= testing::scaled(4, 2); ++seed) {
    GenOptions g;
    g.seed = seed;
    g.blocks[0] = 3, g.blocks[1] = 1 + seed % 3, g.blocks[2] = 2;
    g.block_level = 2;
    g.leaves = leaves;
    g.max_level = 8;
    std::vector<Octant> o;
    EXPECT_OK(generate_octree(g, &o));
    out.push_back(balanced ? reference::balance(o) : o);
    const std::vector<Octant> holed = testing::random_holed(seed, leaves, 8, 0.7);
    out.push_back(balanced ? reference::balance(holed) : holed);
    std::sort(out.back().begin(), out.back().end(),
              [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
  }
  return out;
}

std::string import_only(const std::vector<Octant>& leaves, const testing::TempDir& dir) {
  ImportResult ir;
  EXPECT_OK(write_octant_text(dir.file("o.txt"), leaves, ""));
  EXPECT_OK(import_octants(dir.file("db"), dir.file("o.txt"), ImportOptions{}, &ir));
  return dir.file("db");
}

std::unique_ptr<Explorer> open(const std::string& db) {
  std::unique_ptr<Explorer> ex;
  EXPECT_OK(Explorer::open(db, MemoryBudget(8 << 20), &ex));
  return ex;
}

// Closed intervals of the boxes of a and b on each axis: how many axes they
// overlap with positive length, and whether they meet at all.
struct Meet {
  bool touch = true;
  int positive = 0;
};
Meet meet(const int64_t lo_a[3], int64_t ea, const int64_t lo_b[3], int64_t eb) {
  Meet m;
  for (int i = 0; i < 3; ++i) {
    const int64_t lo = std::max(lo_a[i], lo_b[i]), hi = std::min(lo_a[i] + ea, lo_b[i] + eb);
    if (hi < lo) m.touch = false;
    if (hi > lo) ++m.positive;
  }
  return m;
}

// The leaves across direction d of o, by the definition: a leaf whose
// interior meets the same-size box r across d, and whose closed box meets
// o's closed box within r in a piece of dimension 3 - (crossed axes).
std::vector<uint64_t> across(const std::vector<Octant>& leaves, const Octant& o, Direction d) {
  const int64_t e = octant_edge(o);
  const int64_t r[3] = {o.x + d.dx * e, o.y + d.dy * e, o.z + d.dz * e};
  std::vector<uint64_t> ids;
  for (size_t j = 0; j < leaves.size(); ++j) {
    const Octant& l = leaves[j];
    const int64_t lo[3] = {l.x, l.y, l.z}, el = octant_edge(l);
    if (meet(lo, el, r, e).positive != 3) continue;  // interiors apart
    // The piece of l's closed box inside r's and o's: the intersection of
    // three boxes, axis by axis.
    int dims = 0;
    bool touch = true;
    const int64_t olo[3] = {o.x, o.y, o.z};
    for (int a = 0; a < 3; ++a) {
      const int64_t lo3 = std::max({lo[a], r[a], olo[a]});
      const int64_t hi3 = std::min({lo[a] + el, r[a] + e, olo[a] + e});
      if (hi3 < lo3) touch = false;
      if (hi3 > lo3) ++dims;
    }
    if (touch && dims == 3 - d.nonzero()) ids.push_back(j);
  }
  return ids;
}

TEST(Explore, NeighborsMatchTheDefinitionOnAnyOctree) {
  for (bool balanced : {false, true}) {
    for (const auto& leaves : octrees(balanced, testing::scaled(600, 200))) {
      testing::TempDir dir;
      auto ex = open(import_only(leaves, dir));
      ASSERT_TRUE(ex);
      for (uint64_t id = 0; id < leaves.size(); ++id) {
        std::vector<Neighbor> got;
        ASSERT_OK(ex->neighbors(id, (1u << 1) | (1u << 2) | (1u << 3), &got));
        std::vector<std::pair<std::string, uint64_t>> g, w;
        for (const Neighbor& n : got) {
          g.push_back({direction_name(n.dir), n.id});
          ASSERT_EQ(n.octant, leaves[n.id]);
        }
        for (const Direction& d : kAllDirections) {
          for (uint64_t j : across(leaves, leaves[id], d)) w.push_back({direction_name(d), j});
        }
        ASSERT_EQ(g, w) << "element " << id << " balanced " << balanced;
        // Asking for one kind gives that kind's part of the whole.
        ASSERT_OK(ex->neighbors(id, 1u << 2, &got));
        for (const Neighbor& n : got) ASSERT_EQ(n.dir.nonzero(), 2);
      }
      std::vector<Neighbor> none;
      EXPECT_TRUE(ex->neighbors(leaves.size(), 2, &none).is_invalid_argument());
    }
  }
}

TEST(Explore, NodeElementsAndDependsMatchTheReferenceMesh) {
  for (const auto& leaves : octrees(true, testing::scaled(400, 150))) {
    testing::TempDir dir;
    auto ex = open(testing::build_mesh(leaves, dir));
    ASSERT_TRUE(ex);
    const reference::Mesh ref = reference::extract(leaves);
    ASSERT_EQ(ex->node_count(), ref.nodes.size());
    for (uint64_t id = 0; id < ref.nodes.size(); ++id) {
      const Coord c = ref.nodes[id].c;
      std::vector<std::pair<uint64_t, int>> want;
      for (uint64_t j = 0; j < leaves.size(); ++j) {
        const Octant& l = leaves[j];
        const int64_t e = octant_edge(l);
        const bool holds = l.x <= c.x && c.x <= l.x + e && l.y <= c.y && c.y <= l.y + e &&
                           l.z <= c.z && c.z <= l.z + e;
        if (!holds) continue;
        int corner = -1;
        for (int k = 0; k < 8; ++k) corner = ref.corners[j][k] == id ? k : corner;
        want.push_back({j, corner});
      }
      std::vector<NodeElement> got;
      ASSERT_OK(ex->node_elements(id, &got));
      std::vector<std::pair<uint64_t, int>> g;
      for (const NodeElement& e : got) g.push_back({e.id, e.corner});
      ASSERT_EQ(g, want) << "node " << id;

      std::vector<uint64_t> dependents;
      for (uint64_t m = 0; m < ref.nodes.size(); ++m) {
        const auto& a = ref.nodes[m].anchors;
        if (std::find(a.begin(), a.end(), id) != a.end()) dependents.push_back(m);
      }
      std::vector<MeshNode> deps;
      ASSERT_OK(ex->depends(id, &deps));
      std::vector<uint64_t> d;
      for (const MeshNode& n : deps) d.push_back(n.id);
      ASSERT_EQ(d, dependents) << "node " << id;
    }
    std::vector<NodeElement> none;
    EXPECT_TRUE(ex->node_elements(ref.nodes.size(), &none).is_invalid_argument());
  }
}

TEST(Explore, BatchesAnswerEveryPointInInputOrder) {
  for (const auto& leaves : octrees(true, testing::scaled(3000, 800))) {
    testing::TempDir dir;
    auto ex = open(testing::build_mesh(leaves, dir));
    ASSERT_TRUE(ex);
    const reference::Mesh ref = reference::extract(leaves);
    std::mt19937_64 rng(7);
    std::vector<Coord> points;
    // Inside the blocks, in the root beyond them (a hole), past the root, at
    // nodes and near them, in no order.
    for (int i = 0; i < 3000; ++i) {
      const int what = int(rng() % 4);
      if (what == 0) {
        points.push_back({uint32_t(rng() % (kRootEdge + 9)), uint32_t(rng() % (kRootEdge / 2)),
                          uint32_t(rng() % kRootEdge)});
      } else {
        Coord c = ref.nodes[rng() % ref.nodes.size()].c;
        if (what == 2) c.x += uint32_t(rng() % 3);
        points.push_back(c);
      }
    }
    std::vector<PointHit> hits(points.size());
    std::vector<NodeHit> nodes(points.size());
    ASSERT_OK(ex->locate_batch(points.data(), points.size(), hits.data()));
    ASSERT_OK(ex->node_at_batch(points.data(), points.size(), nodes.data()));
    // A few points at a time take the sparse path (a descent per key): the
    // same answers.
    for (size_t at = 0; at < points.size(); at += 7) {
      const size_t n = std::min<size_t>(7, points.size() - at);
      PointHit few[7];
      NodeHit few_nodes[7];
      ASSERT_OK(ex->locate_batch(points.data() + at, n, few));
      ASSERT_OK(ex->node_at_batch(points.data() + at, n, few_nodes));
      for (size_t k = 0; k < n; ++k) {
        ASSERT_EQ(few[k].inside, hits[at + k].inside);
        ASSERT_EQ(few[k].id, hits[at + k].id);
        ASSERT_EQ(few_nodes[k].found, nodes[at + k].found);
        ASSERT_EQ(few_nodes[k].id, nodes[at + k].id);
      }
    }
    for (size_t i = 0; i < points.size(); ++i) {
      const Coord p = points[i];
      int64_t want = -1;
      for (size_t j = 0; j < leaves.size() && pixel_is_valid(p); ++j) {
        if (octant_contains_point(leaves[j], p)) want = int64_t(j);
      }
      ASSERT_EQ(hits[i].inside, want >= 0) << i;
      if (want >= 0) {
        ASSERT_EQ(hits[i].id, uint64_t(want));
        ASSERT_EQ(hits[i].leaf, leaves[want]);
      }
      int64_t node = -1;
      for (size_t m = 0; m < ref.nodes.size(); ++m) node = ref.nodes[m].c == p ? int64_t(m) : node;
      ASSERT_EQ(nodes[i].found, node >= 0) << i;
      if (node >= 0) {
        ASSERT_EQ(nodes[i].id, uint64_t(node));
        ASSERT_EQ(nodes[i].kind, ref.nodes[node].kind);
      }
    }
  }
}

// A batch shared among Explorers (cut by key range into runs, each sorted
// and walked by one) answers every point as one Explorer's batch does
// (checked against brute force above): points spread over the root, points
// crowded at a few nodes (runs of uneven bins), and one point many times
// (every key in one bin: the other runs empty).
TEST(Explore, SharedBatchesAnswerAsOneExplorer) {
  const auto trees = octrees(true, testing::scaled(3000, 800));
  for (size_t t = 0; t < trees.size(); t += 2) {
    testing::TempDir dir;
    const std::string db = testing::build_mesh(trees[t], dir);
    std::vector<std::unique_ptr<Explorer>> all(3);
    for (auto& e : all) e = open(db);
    SharedBatch shared({all[0].get(), all[1].get(), all[2].get()});
    const reference::Mesh ref = reference::extract(trees[t]);
    std::mt19937_64 rng(t + 3);
    std::vector<Coord> spread, crowded, same(SharedBatch::kParallelPoints + 5, ref.nodes[0].c);
    for (size_t i = 0; i < 2 * SharedBatch::kParallelPoints; ++i) {
      spread.push_back({uint32_t(rng() % (kRootEdge + 9)), uint32_t(rng() % kRootEdge),
                        uint32_t(rng() % kRootEdge)});
      Coord c = ref.nodes[rng() % 5].c;
      c.y += uint32_t(rng() % 2);
      crowded.push_back(c);
    }
    for (const auto* points : {&spread, &crowded, &same}) {
      const size_t n = points->size();
      std::vector<PointHit> want(n), got(n);
      std::vector<NodeHit> want_nodes(n), got_nodes(n);
      ASSERT_OK(all[0]->locate_batch(points->data(), n, want.data()));
      ASSERT_OK(all[0]->node_at_batch(points->data(), n, want_nodes.data()));
      ASSERT_OK(shared.locate(points->data(), n, got.data()));
      ASSERT_OK(shared.node_at(points->data(), n, got_nodes.data()));
      size_t inside = 0;
      for (size_t i = 0; i < n; ++i) {
        ASSERT_EQ(got[i].inside, want[i].inside) << i;
        ASSERT_EQ(got[i].id, want[i].id) << i;
        ASSERT_EQ(got_nodes[i].found, want_nodes[i].found) << i;
        ASSERT_EQ(got_nodes[i].id, want_nodes[i].id) << i;
        inside += got[i].inside;
      }
      EXPECT_GT(inside, n / 50);  // the batch is not all outside
    }
  }
}

TEST(Explore, ElementsAndNodesByIdMatchTheReferenceMesh) {
  testing::TempDir dir;
  const std::vector<Octant> leaves = testing::small_sphere();
  auto ex = open(testing::build_mesh(leaves, dir));
  ASSERT_TRUE(ex);
  const reference::Mesh ref = reference::extract(leaves);
  for (uint64_t id = 0; id < ref.elements.size(); id += 7) {
    MeshElement e;
    ASSERT_OK(ex->element(id, &e));
    ASSERT_EQ(e.octant, ref.elements[id]);
    ASSERT_EQ(e.nodes, ref.corners[id]);
  }
  for (uint64_t id = 0; id < ref.nodes.size(); id += 5) {
    MeshNode n;
    ASSERT_OK(ex->node(id, &n));
    ASSERT_EQ(n.c, ref.nodes[id].c);
    ASSERT_EQ(n.kind, ref.nodes[id].kind);
    ASSERT_EQ(std::vector<uint64_t>(n.anchors.begin(), n.anchors.begin() + n.anchor_count),
              ref.nodes[id].anchors);
  }
  MeshElement e;
  MeshNode n;
  EXPECT_TRUE(ex->element(ref.elements.size(), &e).is_invalid_argument());
  EXPECT_TRUE(ex->node(ref.nodes.size(), &n).is_invalid_argument());
}

// Random points spread over a table of a few hundred leaf pages, about one
// to a page, sorted: the batch is shown sparse by its first window (64 points)
// and asks the rest key by key, so it decodes no more than that window's
// pages (a first window of 1024 decoded nearly every page here), and its
// answers are those of one question a point.
TEST(Explore, ASparseBatchDecodesOnlyItsFirstWindowsPages) {
  GenOptions g;
  g.seed = 5;
  g.leaves = testing::scaled(200000, 100000);
  g.max_level = 12;
  std::vector<Octant> leaves;
  ASSERT_OK(generate_octree(g, &leaves));
  testing::TempDir dir;
  // Plain pages (about 500 keys each): hundreds of pages from few leaves.
  ImportOptions io;
  io.packed = false;
  ImportResult ir;
  ASSERT_OK(write_octant_text(dir.file("o.txt"), leaves, ""));
  ASSERT_OK(import_octants(dir.file("db"), dir.file("o.txt"), io, &ir));
  auto ex = open(dir.file("db"));
  ASSERT_TRUE(ex);
  std::mt19937_64 rng(11);
  std::vector<Coord> points(testing::scaled(500, 250));
  for (Coord& c : points) {
    c = {uint32_t(rng() % kRootEdge), uint32_t(rng() % kRootEdge), uint32_t(rng() % kRootEdge)};
  }
  std::vector<PointHit> hits(points.size());
  ASSERT_OK(ex->locate_batch(points.data(), points.size(), hits.data()));
  EXPECT_LE(ex->octant_pages_decoded(), 64u);
  EXPECT_GT(ex->octant_pages_decoded(), 8u);  // the first window was walked dense
  for (size_t i = 0; i < points.size(); ++i) {
    PointHit one;
    ASSERT_OK(ex->locate(points[i], &one));
    ASSERT_EQ(hits[i].inside, one.inside) << i;
    ASSERT_EQ(hits[i].id, one.id) << i;
    ASSERT_EQ(hits[i].leaf, one.leaf) << i;
  }
}

}  // namespace
}  // namespace weaver
