// The sort-based extractor against the brute-force reference, node for node
// (id, coordinate, kind, anchors), on many generated balanced octrees.
#include "extract/extract.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include "db/database.h"
#include "db/leaf_reader.h"
#include "db/node_table.h"
#include "export/export.h"
#include "extract/bucket_worker.h"
#include "gen/octree_gen.h"
#include "import/import.h"
#include "import/octant_text.h"
#include "reference/reference_mesh.h"
#include "test_octrees.h"
#include "test_util.h"
#include "verify/verify.h"

namespace weaver {
namespace {

struct Case {
  std::string name;
  std::vector<Octant> leaves;  // balanced
};

using testing::random_balanced;

// Refines every leaf that touches a sphere, to `depth` levels (grading).
std::vector<Octant> graded_sphere(int base, int depth, double radius_frac) {
  std::vector<Octant> leaves;
  std::vector<Octant> todo = {octant_root()};
  const double r = radius_frac * kRootEdge, cx = kRootEdge / 2.0;
  while (!todo.empty()) {
    const Octant o = todo.back();
    todo.pop_back();
    const double e = octant_edge(o);
    // Distance range from the centre to the box decides whether it meets the sphere.
    double dmin = 0, dmax = 0;
    const double lo[3] = {double(o.x), double(o.y), double(o.z)};
    for (int a = 0; a < 3; ++a) {
      const double near = std::max(lo[a] - cx, std::max(0.0, cx - (lo[a] + e)));
      const double far = std::max(std::abs(lo[a] - cx), std::abs(lo[a] + e - cx));
      dmin += near * near;
      dmax += far * far;
    }
    const bool meets = std::sqrt(dmin) <= r && r <= std::sqrt(dmax);
    if (o.level < base || (meets && o.level < base + depth)) {
      for (int k = 0; k < 8; ++k) todo.push_back(octant_child(o, k));
    } else {
      leaves.push_back(o);
    }
  }
  return reference::balance(leaves);
}

class ExtractTest : public ::testing::Test {
 protected:
  // Imports leaves into a fresh database and extracts with the options.
  Status extract(const std::vector<Octant>& leaves, const ExtractOptions& o, ExtractResult* r) {
    db_ = dir_.file("db" + std::to_string(count_++));
    const std::string text = db_ + ".txt";
    WEAVER_RETURN_IF_ERROR(write_octant_text(text, leaves, ""));
    ImportResult ir;
    WEAVER_RETURN_IF_ERROR(import_octants(db_, text, ImportOptions{}, &ir));
    return extract_mesh(db_, o, r);
  }

  void compare_with_reference(const std::vector<Octant>& leaves, const ExtractOptions& o) {
    ExtractResult r;
    ASSERT_OK(extract(leaves, o, &r));
    const reference::Mesh ref = reference::extract(leaves);
    ASSERT_EQ(r.elements, ref.elements.size());
    ASSERT_EQ(r.nodes, ref.nodes.size());
    std::unique_ptr<Database> db;
    std::unique_ptr<BTree> nodes;
    ASSERT_OK(Database::open(db_, Database::Mode::kRead, false, &db));
    ASSERT_OK(db->open_table(kNodeTable, 1 << 20, &nodes));
    BTreeCursor c;
    ASSERT_OK(nodes->seek_cursor(0, &c));
    uint64_t anchored = 0, edge = 0, face = 0;
    for (uint64_t id = 0; id < ref.nodes.size(); ++id) {
      ASSERT_TRUE(c.valid());
      const reference::MeshNode& want = ref.nodes[id];
      const Coord got = morton_decode(c.key());
      ASSERT_EQ(got, want.c) << "node " << id;
      const auto kind = static_cast<NodeKind>(c.payload()[0]);
      ASSERT_EQ(kind, want.kind) << "node " << id << " at " << got.x << " " << got.y << " "
                                 << got.z;
      Coord anchors[4];
      const int n = node_anchors(got, kind, anchors);
      ASSERT_EQ(static_cast<size_t>(n), want.anchors.size());
      for (int i = 0; i < n; ++i) {
        uint64_t anchor_id = 0;
        ASSERT_OK(nodes->rank(node_key(anchors[i]), &anchor_id));
        ASSERT_EQ(anchor_id, want.anchors[i]) << "anchor " << i << " of node " << id;
      }
      anchored += kind == NodeKind::kAnchored;
      edge += kind == NodeKind::kEdge;
      face += kind == NodeKind::kFace;
      ASSERT_OK(c.next());
    }
    EXPECT_FALSE(c.valid());
    EXPECT_EQ(r.anchored, anchored);
    EXPECT_EQ(r.edge, edge);
    EXPECT_EQ(r.face, face);
  }

  testing::TempDir dir_;
  std::string db_;
  int count_ = 0;
};

TEST_F(ExtractTest, SphereAndPointGeneratorsAreBalancedByConstruction) {
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    GenOptions g;
    g.seed = seed;
    g.level = 1;
    g.max_level = 5;
    g.kind = seed % 2 ? GenOptions::Kind::kSphere : GenOptions::Kind::kPoints;
    g.radius = 0.1 + 0.05 * seed;
    g.points = 3 * seed;
    std::vector<Octant> leaves;
    ASSERT_OK(generate_octree(g, &leaves));
    ASSERT_EQ(reference::balance(leaves), leaves) << "seed " << seed;  // nothing to split
    ASSERT_NO_FATAL_FAILURE(compare_with_reference(leaves, ExtractOptions{}));
  }
}

// Level 4 is a block of 4096 leaves, the deepest whose corners the
// workers make as a lattice (bucket_worker.cc's kMostBlockDepth), and level
// 5 eight of them.
TEST_F(ExtractTest, SingleElementAndUniformGrids) {
  for (int level : {0, 1, 2, 3, 4, 5}) {
    GenOptions g;
    g.kind = GenOptions::Kind::kUniform;
    g.level = level;
    std::vector<Octant> leaves;
    ASSERT_OK(generate_octree(g, &leaves));
    ExtractOptions o;
    ASSERT_NO_FATAL_FAILURE(compare_with_reference(leaves, o));
  }
}

TEST_F(ExtractTest, LeavesAtLevel20) {
  // A tiny corner refined all the way down.
  std::vector<Octant> leaves = {octant_root()};
  for (int step = 0; step < 20; ++step) {
    const Octant o = leaves.front();
    leaves.erase(leaves.begin());
    for (int k = 7; k >= 0; --k) leaves.insert(leaves.begin(), octant_child(o, k));
  }
  ExtractOptions o;
  ASSERT_NO_FATAL_FAILURE(compare_with_reference(reference::balance(leaves), o));
}

TEST_F(ExtractTest, RandomBalancedOctreesAcrossDomainsAndBudgets) {
  std::mt19937_64 rng(99);
  const int cases = static_cast<int>(testing::scaled(200, 25));
  for (int t = 0; t < cases; ++t) {
    const int block_level = static_cast<int>(rng() % 3);
    const uint32_t per_axis = 1u << block_level;
    const uint32_t bx = 1 + rng() % per_axis, by = 1 + rng() % per_axis, bz = 1 + rng() % per_axis;
    const uint64_t target = 20 + rng() % 400;
    const int max_level = block_level + 1 + static_cast<int>(rng() % 8);
    const auto leaves = random_balanced(rng(), bx, by, bz, block_level, target, max_level);
    ExtractOptions o;
    // Even cases: the paper's buckets, from one bucket to tiny ones; odd
    // cases: buckets of 1 to ~all leaves.
    if (t % 2 == 0) {
      o.buckets = ExtractOptions::Buckets::kLevel;
      o.bucket_level = static_cast<int>(rng() % (max_level + 2));
    } else {
      o.bucket_leaves = 1 + rng() % (rng() % 2 ? 8 : leaves.size());
    }
    o.memory = MemoryBudget(1 << 16);  // forces spill files
    SCOPED_TRACE("case " + std::to_string(t) + ": " + std::to_string(leaves.size()) +
                 " leaves, blocks " + std::to_string(bx) + "x" + std::to_string(by) + "x" +
                 std::to_string(bz) + " at level " + std::to_string(block_level) +
                 ", bucket level " + std::to_string(o.bucket_level) + ", bucket leaves " +
                 std::to_string(o.bucket_leaves));
    ASSERT_NO_FATAL_FAILURE(compare_with_reference(leaves, o));
  }
}

// Imported octrees need not fill their parents: leaves left out of random
// octrees make holes as fine as the leaves, and nodes on a hole's boundary
// are classified by the elements that are there.
TEST_F(ExtractTest, HolesAsFineAsTheLeaves) {
  std::mt19937_64 rng(23);
  const int cases = static_cast<int>(testing::scaled(120, 20));
  int chained = 0;
  for (int t = 0; t < cases; ++t) {
    const uint64_t seed = rng(), count = 30 + rng() % 300;
    const int max_level = 3 + static_cast<int>(rng() % 6);
    const std::vector<Octant> holed = testing::random_holed(seed, count, max_level, 0.75);
    if (holed.empty()) continue;
    const std::vector<Octant> leaves = reference::balance(holed);
    ExtractOptions o;
    o.bucket_leaves = 1 + rng() % (rng() % 2 ? 8 : leaves.size());
    o.memory = MemoryBudget(1 << 16);
    o.threads = 1 + t % 2;
    if (t % 3 == 2) o.algorithm = ExtractOptions::Algorithm::kSearch;
    SCOPED_TRACE("case " + std::to_string(t) + ": " + std::to_string(leaves.size()) + " leaves");
    ASSERT_NO_FATAL_FAILURE(compare_with_reference(leaves, o));
    // Verify classifies every node again its own way and agrees; all it
    // may find is a dangling node whose anchor dangles too, which holes
    // allow (DESIGN.md promises anchored anchors for filled parents only).
    VerifyReport report;
    ASSERT_OK(verify_database(db_, VerifyOptions{}, &report));
    EXPECT_TRUE(report.mesh_checked);
    for (const std::string& p : report.problems) {
      ASSERT_NE(p.find("is not anchored (it dangles too"), std::string::npos) << p;
    }
    chained += !report.ok();
  }
  EXPECT_GT(chained, 0);  // such chains do occur, and verify names them
}

TEST_F(ExtractTest, GradedAroundASphereWithManyBucketsAndSpillFiles) {
  const auto leaves = graded_sphere(2, testing::small_scale() ? 3 : 4, 0.3);
  for (int bucket_level : {-1, 3, 5}) {
    ExtractOptions o;
    o.buckets = ExtractOptions::Buckets::kLevel;
    o.bucket_level = bucket_level;
    o.memory = MemoryBudget(1 << 14);  // a tiny cap: spills go through files
    ASSERT_NO_FATAL_FAILURE(compare_with_reference(leaves, o));
  }
  for (uint64_t bucket_leaves : {7, 100, 5000}) {
    ExtractOptions o;
    o.bucket_leaves = bucket_leaves;
    o.memory = MemoryBudget(1 << 14);
    ASSERT_NO_FATAL_FAILURE(compare_with_reference(leaves, o));
  }
  for (auto buckets : {ExtractOptions::Buckets::kLevel, ExtractOptions::Buckets::kLeaves}) {
    ExtractOptions o;
    o.buckets = buckets;
    o.bucket_level = 5;
    o.bucket_leaves = 16;
    o.memory = MemoryBudget(1 << 14);
    ExtractResult r;
    ASSERT_OK(extract(leaves, o, &r));
    EXPECT_GT(r.buckets, 100u);  // 282 and more on the sanitizers' small scale
    EXPECT_GT(r.spilled_to_disk, 0u);
    EXPECT_GT(r.edge + r.face, 0u);
  }
}

// Blocks of 4096 leaves (the deepest the workers make as lattices) next to
// finer leaves: a uniform level-5 grid refined one level more around a
// corner (balanced as made: neighbours differ by a level at most), so that
// the level-1 octants far from it stay whole blocks of 8^4 leaves and those
// near it are cut, at buckets that do and do not hold a whole block.
TEST_F(ExtractTest, BlocksOf4096LeavesBesideFinerOnes) {
  std::vector<Octant> leaves;
  std::vector<Octant> todo = {octant_root()};
  const double c = 0.8 * kRootEdge, r = 0.1 * kRootEdge;
  while (!todo.empty()) {
    const Octant o = todo.back();
    todo.pop_back();
    const double e = octant_edge(o);
    double d2 = 0;  // the squared distance from (c, c, c) to the octant's box
    for (double lo : {double(o.x), double(o.y), double(o.z)}) {
      const double gap = std::max(0.0, std::max(lo - c, c - (lo + e)));
      d2 += gap * gap;
    }
    if (o.level < 5 || (o.level < 6 && d2 <= r * r)) {
      for (int k = 0; k < 8; ++k) todo.push_back(octant_child(o, k));
    } else {
      leaves.push_back(o);
    }
  }
  std::sort(leaves.begin(), leaves.end(),
            [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
  for (uint64_t bucket_leaves : {0, 3000, 20000}) {
    ExtractOptions o;
    o.bucket_leaves = bucket_leaves;
    SCOPED_TRACE("bucket leaves " + std::to_string(bucket_leaves));
    ASSERT_NO_FATAL_FAILURE(compare_with_reference(leaves, o));
  }
}

// Buckets of about K leaves hold K to 1.25 K leaves (the last one fewer).
// At the same budget they spill less than the paper's buckets on a graded
// octree, whose buckets are sized for the finest leaves everywhere.
// The nodes on the root's far faces have codes past every leaf's; they come
// last, in buckets of bounded size, not all in the last bucket of leaves
// (which at 2 Hz held 100 MB more than --memory 64M).  A uniform grid of
// level 6 has 8385 such nodes; buckets of 256 leaves take at most a few
// hundred spilled corners each, and the tail's buckets about 1536.
TEST_F(ExtractTest, TheNodesPastTheLastLeafComeInBucketsOfBoundedSize) {
  GenOptions g;
  g.kind = GenOptions::Kind::kUniform;
  g.level = 6;
  std::vector<Octant> leaves;
  ASSERT_OK(generate_octree(g, &leaves));
  ExtractOptions o;
  o.bucket_leaves = 256;
  ExtractResult r;
  ASSERT_OK(extract(leaves, o, &r));
  std::unique_ptr<Database> db;
  std::unique_ptr<BTree> octants;
  ASSERT_OK(Database::open(db_, Database::Mode::kRead, false, &db));
  ASSERT_OK(db->open_table(kOctantTable, 1 << 20, &octants));
  LeafReader cursor;
  ASSERT_OK(cursor.open(*octants));
  testing::TempDir scratch;
  SpillStore spills(scratch.file("spill"), 1 << 20);
  BucketReader reader(cursor, BucketPolicy{-1, 256}, spills);
  BucketTask task;
  uint64_t tail_buckets = 0, tail_nodes = 0, last_end = 0;
  for (bool more = true;;) {
    ASSERT_OK(reader.next(&task, &more));
    if (!more) break;
    EXPECT_EQ(task.start, last_end);
    EXPECT_LT(task.start, task.end);
    EXPECT_LE(task.incoming.size(), 1536u + 8) << "bucket from " << task.start;
    if (task.leaf_keys.empty()) ++tail_buckets, tail_nodes += task.incoming.size();
    last_end = task.end;
  }
  EXPECT_EQ(last_end, UINT64_MAX);
  EXPECT_GE(tail_buckets, 5u);
  EXPECT_GE(tail_nodes, 8385u);  // every far-face node, with the masks of its leaves
  EXPECT_EQ(r.nodes, 65u * 65 * 65);
}

TEST_F(ExtractTest, LeafCountBucketsAreEvenAndSpillLessOnGradedOctrees) {
  const auto leaves = graded_sphere(2, testing::small_scale() ? 3 : 4, 0.3);
  ExtractOptions o;
  o.bucket_leaves = 500;
  ExtractResult r;
  ASSERT_OK(extract(leaves, o, &r));
  EXPECT_EQ(r.bucket_leaves, 500u);
  EXPECT_LE(r.buckets, (leaves.size() + 499) / 500);
  EXPECT_GE(r.buckets, leaves.size() / 625);
  o.bucket_leaves = 0;
  o.memory = MemoryBudget(1 << 17);
  ExtractResult counted, paper;
  ASSERT_OK(extract(leaves, o, &counted));
  o.buckets = ExtractOptions::Buckets::kLevel;
  ASSERT_OK(extract(leaves, o, &paper));
  EXPECT_GE(paper.bucket_level, 0);
  EXPECT_EQ(paper.nodes, counted.nodes);
  EXPECT_LT(counted.buckets, paper.buckets);
  EXPECT_LT(counted.spilled, paper.spilled);
  std::printf("%zu leaves: %llu buckets spilled %llu; paper's %llu at level %d spilled %llu\n",
              leaves.size(), (unsigned long long)counted.buckets,
              (unsigned long long)counted.spilled, (unsigned long long)paper.buckets,
              paper.bucket_level, (unsigned long long)paper.spilled);
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// nodes.csv and elements.csv of the database, concatenated.
std::string exported(const std::string& db) {
  ExportOptions o;
  o.nodes_path = db + "-nodes.csv";
  o.elements_path = db + "-elements.csv";
  ExportResult r;
  EXPECT_OK(export_mesh(db, o, &r));
  return file_bytes(o.nodes_path) + file_bytes(o.elements_path);
}

// Odd cases use the LSM as the node store: with this budget its memtable
// flushes every few hundred nodes, so lookups go through many runs.
TEST_F(ExtractTest, SearchAlgorithmMatchesReferenceAndSortByteForByte) {
  std::mt19937_64 rng(7);
  const int cases = static_cast<int>(testing::scaled(30, 8));
  for (int t = 0; t < cases; ++t) {
    const int block_level = static_cast<int>(rng() % 3);
    const uint32_t per_axis = 1u << block_level;
    const auto leaves = random_balanced(rng(), 1 + rng() % per_axis, 1 + rng() % per_axis,
                                        1 + rng() % per_axis, block_level, 20 + rng() % 300,
                                        block_level + 2 + static_cast<int>(rng() % 6));
    SCOPED_TRACE("case " + std::to_string(t));
    ExtractOptions search;
    search.algorithm = ExtractOptions::Algorithm::kSearch;
    search.memory = MemoryBudget(1 << 16);  // a small pool: the node B-tree lives on disk
    search.store = t % 2 ? ExtractOptions::Store::kLsm : ExtractOptions::Store::kBTree;
    ASSERT_NO_FATAL_FAILURE(compare_with_reference(leaves, search));
    std::unique_ptr<Database> db;
    ASSERT_OK(Database::open(db_, Database::Mode::kRead, false, &db));
    const std::string search_table = file_bytes(db->table_path(kNodeTable));
    db.reset();
    const std::string search_csv = exported(db_);
    ExtractResult r;
    ASSERT_OK(extract_mesh(db_, ExtractOptions{}, &r));  // sort, same database
    ASSERT_OK(Database::open(db_, Database::Mode::kRead, false, &db));
    ASSERT_EQ(file_bytes(db->table_path(kNodeTable)), search_table);
    ASSERT_EQ(exported(db_), search_csv);
  }
}

TEST_F(ExtractTest, ThreadCountsOneToFourGiveTheSameNodeTable) {
  std::mt19937_64 rng(41);
  const int cases = static_cast<int>(testing::scaled(12, 4));
  for (int t = 0; t < cases; ++t) {
    const auto leaves = random_balanced(rng(), 1 + rng() % 4, 1 + rng() % 4, 1 + rng() % 4, 2,
                                        50 + rng() % 400, 4 + static_cast<int>(rng() % 5));
    SCOPED_TRACE("case " + std::to_string(t));
    std::string first;
    for (int threads = 1; threads <= 4; ++threads) {
      ExtractOptions o;
      o.threads = threads;
      if (t % 2) {
        o.buckets = ExtractOptions::Buckets::kLevel;
        o.bucket_level = 3 + static_cast<int>(rng() % 3);  // many buckets in flight
      } else {
        o.bucket_leaves = 1 + rng() % 40;
      }
      o.memory = MemoryBudget(1 << 16);
      if (threads == 1) {
        ASSERT_NO_FATAL_FAILURE(compare_with_reference(leaves, o));
      } else {
        ExtractResult r;
        ASSERT_OK(extract_mesh(db_, o, &r));
        EXPECT_EQ(r.elements, leaves.size());
      }
      std::unique_ptr<Database> db;
      ASSERT_OK(Database::open(db_, Database::Mode::kRead, false, &db));
      const std::string table = file_bytes(db->table_path(kNodeTable));
      if (threads == 1) first = table;
      ASSERT_EQ(table, first) << threads << " threads";
    }
  }
  // An unbalanced octree is refused with threads too.
  std::vector<Octant> bad;
  for (int k = 1; k < 8; ++k) bad.push_back(octant_child(octant_root(), k));
  const Octant c0 = octant_child(octant_root(), 0);
  for (int k = 0; k < 7; ++k) bad.push_back(octant_child(c0, k));
  for (int j = 0; j < 8; ++j) bad.push_back(octant_child(octant_child(c0, 7), j));
  ExtractOptions o;
  o.threads = 3;
  o.buckets = ExtractOptions::Buckets::kLevel;
  o.bucket_level = 2;
  ExtractResult r;
  EXPECT_TRUE(extract(bad, o, &r).is_invalid_argument());
}

// An octant table written directly (import would refuse the overlap, and
// writes level counts that this table lacks: extract must scan instead).
void write_raw_keys(const std::string& dir, std::vector<uint64_t> keys) {
  std::unique_ptr<Database> db;
  ASSERT_OK(Database::open(dir, Database::Mode::kWrite, true, &db));
  std::unique_ptr<BTree> t;
  std::string file;
  ASSERT_OK(db->create_table(kOctantTable, TableOptions{}, 1 << 20, &t, &file));
  std::sort(keys.begin(), keys.end());
  for (uint64_t k : keys) ASSERT_OK(t->append(k, nullptr));
  ASSERT_OK(t->commit());
  ASSERT_OK(db->commit({{kOctantTable, file}}));
}

void write_raw_octant_table(const std::string& dir, const std::vector<Octant>& octants) {
  std::vector<uint64_t> keys;
  for (const Octant& o : octants) keys.push_back(octant_key(o));
  write_raw_keys(dir, keys);
}

TEST_F(ExtractTest, RefusesOverlappingOctantsAndScansTablesWithoutLevelCounts) {
  std::vector<Octant> leaves;
  for (int k = 0; k < 8; ++k) leaves.push_back(octant_child(octant_root(), k));
  const std::string good = dir_.file("raw-good");
  ASSERT_NO_FATAL_FAILURE(write_raw_octant_table(good, leaves));
  ExtractResult r;
  ASSERT_OK(extract_mesh(good, ExtractOptions{}, &r));
  EXPECT_EQ(r.nodes, 27u);
  leaves.push_back(octant_child(leaves[3], 5));  // inside leaf 3
  const std::string bad = dir_.file("raw-bad");
  ASSERT_NO_FATAL_FAILURE(write_raw_octant_table(bad, leaves));
  // Buckets of one level read leaf by leaf; buckets of a leaf count read a
  // leaf page's keys at a time (LeafReader::take), the overlap mid-page.
  for (int threads : {1, 2}) {
    for (auto algorithm : {ExtractOptions::Algorithm::kSort, ExtractOptions::Algorithm::kSearch}) {
      for (auto buckets : {ExtractOptions::Buckets::kLevel, ExtractOptions::Buckets::kLeaves}) {
        ExtractOptions o;
        o.threads = threads;
        o.algorithm = algorithm;
        o.buckets = buckets;
        o.bucket_level = buckets == ExtractOptions::Buckets::kLevel ? 2 : -1;
        const Status st = extract_mesh(bad, o, &r);
        ASSERT_TRUE(st.is_invalid_argument()) << st.to_string();
        EXPECT_NE(st.message().find("(524288 524288 0 1) and (786432 524288 262144 2) overlap"),
                  std::string::npos)
            << st.message();
      }
    }
  }
}

// A key no octant has, mid-page (a level 1 code with bits below its cell,
// and a slot no level has), is named as corrupt however the leaves are read.
TEST_F(ExtractTest, RefusesInvalidOctantKeysMidPage) {
  std::vector<uint64_t> keys;
  for (int k = 0; k < 8; ++k) keys.push_back(octant_key(octant_child(octant_root(), k)));
  const uint64_t misaligned = keys[3] + (uint64_t{1} << 7), bad_slot = (keys[5] + 128) | 28;
  for (uint64_t invalid : {misaligned, bad_slot}) {
    ASSERT_FALSE(octant_key_is_valid(invalid));
    std::vector<uint64_t> with = keys;
    with.push_back(invalid);
    const std::string bad = dir_.file("raw-invalid-" + std::to_string(invalid));
    ASSERT_NO_FATAL_FAILURE(write_raw_keys(bad, with));
    for (int threads : {1, 2}) {
      for (auto buckets : {ExtractOptions::Buckets::kLevel, ExtractOptions::Buckets::kLeaves}) {
        ExtractOptions o;
        o.threads = threads;
        o.buckets = buckets;
        o.bucket_level = buckets == ExtractOptions::Buckets::kLevel ? 2 : -1;
        ExtractResult r;
        const Status st = extract_mesh(bad, o, &r);
        ASSERT_TRUE(st.is_corruption()) << st.to_string();
        EXPECT_NE(st.message().find("invalid octant key " + std::to_string(invalid)),
                  std::string::npos)
            << st.message();
      }
    }
  }
}

TEST_F(ExtractTest, RefusesUnbalancedOctreesNamingTwoOctants) {
  // The root split once, then one child refined two more levels: 4x jump.
  std::vector<Octant> leaves;
  for (int k = 1; k < 8; ++k) leaves.push_back(octant_child(octant_root(), k));
  const Octant first = octant_child(octant_root(), 0);
  for (int k = 0; k < 8; ++k) {
    const Octant c = octant_child(first, k);
    if (k == 7) {
      for (int j = 0; j < 8; ++j) leaves.push_back(octant_child(c, j));
    } else {
      leaves.push_back(c);
    }
  }
  for (auto algorithm : {ExtractOptions::Algorithm::kSort, ExtractOptions::Algorithm::kSearch}) {
    ExtractOptions o;
    o.algorithm = algorithm;
    ExtractResult r;
    const Status st = extract(leaves, o, &r);
    ASSERT_TRUE(st.is_invalid_argument()) << st.to_string();
    EXPECT_NE(st.message().find("not 2:1 balanced"), std::string::npos) << st.message();
    EXPECT_NE(st.message().find("(524288"), std::string::npos) << st.message();
  }
  // The database keeps no node table.
  std::unique_ptr<Database> db;
  ASSERT_OK(Database::open(db_, Database::Mode::kRead, false, &db));
  EXPECT_FALSE(db->has_table(kNodeTable));
}

}  // namespace
}  // namespace weaver
