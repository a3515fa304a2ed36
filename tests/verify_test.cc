// weaver verify: passes reference meshes, and names each kind of damage.
#include "verify/verify.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include "bench_util.h"
#include "db/database.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "gen/octree_gen.h"
#include "import/import.h"
#include "import/octant_text.h"
#include "reference/reference_mesh.h"
#include "test_octrees.h"
#include "test_util.h"

namespace weaver {
namespace {

using Nodes = std::vector<std::pair<uint64_t, NodeKind>>;

using testing::random_balanced;

class VerifyTest : public ::testing::Test {
 protected:
  // A database holding the leaves and the node table of the reference mesh
  // (written directly, so verify is checked against the reference, not
  // against our extractor).
  void build(const std::vector<Octant>& leaves) {
    db_ = dir_.file("db" + std::to_string(count_++));
    const std::string text = db_ + ".txt";
    ASSERT_OK(write_octant_text(text, leaves, ""));
    ImportResult ir;
    ASSERT_OK(import_octants(db_, text, ImportOptions{}, &ir));
    const reference::Mesh ref = reference::extract(leaves);
    nodes_.clear();
    for (const reference::MeshNode& n : ref.nodes) nodes_.emplace_back(node_key(n.c), n.kind);
    write_nodes(nodes_);
    elements_ = ref.elements;
  }

  void write_nodes(const Nodes& nodes) {
    std::unique_ptr<Database> db;
    ASSERT_OK(Database::open(db_, Database::Mode::kWrite, false, &db));
    TableOptions o;
    o.key_kind = KeyKind::kNode;
    std::string error;
    o.schema = *RecordSchema::parse(kNodeSchema, &error);
    std::unique_ptr<BTree> t;
    std::string file;
    ASSERT_OK(db->create_table(kNodeTable, o, 1 << 20, &t, &file));
    Status built;
    for (const auto& [key, kind] : nodes) {
      const auto b = static_cast<std::byte>(kind);
      if (built.ok()) built = t->append(key, &b);
    }
    if (built.ok()) built = t->commit();
    ASSERT_OK(db->publish(kNodeTable, file, t, built));
  }

  // independent: every node classified from the leaves around it, rather
  // than the derived nodes compared (VerifyOptions::independent).
  VerifyReport verify(int threads = 1, bool independent = false) {
    VerifyReport r;
    VerifyOptions o;
    o.memory = MemoryBudget(8 << 20);
    o.threads = threads;
    o.independent = independent;
    EXPECT_OK(verify_database(db_, o, &r));
    return r;
  }

  void expect_problem(const std::string& needle) {
    const VerifyReport r = verify();
    EXPECT_EQ(verify(3).problems, r.problems);  // the same report on 3 threads
    ASSERT_FALSE(r.ok()) << "expected a problem mentioning '" << needle << "'";
    bool seen = false;
    for (const std::string& p : r.problems) seen = seen || p.find(needle) != std::string::npos;
    EXPECT_TRUE(seen) << "first problem: " << r.problems[0] << "\nexpected: " << needle;
    // The independent check finds it too.
    const VerifyReport each = verify(2, true);
    seen = false;
    for (const std::string& p : each.problems) seen = seen || p.find(needle) != std::string::npos;
    EXPECT_TRUE(seen) << "--independent: " << (each.ok() ? "no problem" : each.problems[0]);
  }

  size_t find_kind(NodeKind k, uint64_t seed) const {
    std::vector<size_t> of_kind;
    for (size_t i = 0; i < nodes_.size(); ++i)
      if (nodes_[i].second == k) of_kind.push_back(i);
    EXPECT_FALSE(of_kind.empty());
    return of_kind.empty() ? 0 : of_kind[seed % of_kind.size()];
  }

  // The octant table written again with level counts in its metadata that
  // put every leaf at level 3 (false).  The node table derived from the
  // octants is dropped with them.
  void claim_false_level_counts() {
    std::unique_ptr<Database> db;
    ASSERT_OK(Database::open(db_, Database::Mode::kWrite, false, &db));
    std::unique_ptr<BTree> old_t, t;
    ASSERT_OK(db->open_table(kOctantTable, 1 << 20, &old_t));
    TableOptions o = old_t->options();
    LevelCounts levels{};
    levels[3] = old_t->size();
    o.metadata = levels_to_metadata(levels);
    std::string file;
    ASSERT_OK(db->create_table(kOctantTable, o, 1 << 20, &t, &file));
    BTreeCursor c;
    ASSERT_OK(old_t->seek_cursor(0, &c));
    Status built;
    for (; c.valid() && built.ok(); built = c.next()) built = t->append(c.key(), c.payload());
    if (built.ok()) built = t->commit();
    ASSERT_OK(db->publish(kOctantTable, file, t, built));
  }

  std::string table_file(const std::string& name) {
    std::unique_ptr<Database> db;
    EXPECT_OK(Database::open(db_, Database::Mode::kRead, false, &db));
    return db->table_path(name);
  }

  testing::TempDir dir_;
  std::string db_;
  Nodes nodes_;
  std::vector<Octant> elements_;  // of the reference mesh, in id order
  int count_ = 0;
};

TEST_F(VerifyTest, ReferenceMeshesPassWithTheirCounts) {
  const int cases = static_cast<int>(testing::scaled(40, 8));
  for (int i = 0; i < cases; ++i) {
    std::mt19937_64 rng(i);
    const uint32_t bx = 1 + rng() % 3, by = 1 + rng() % 3, bz = 1 + rng() % 2;
    const int block_level = 2;
    ASSERT_NO_FATAL_FAILURE(build(random_balanced(i, bx, by, bz, block_level, 300 + rng() % 3000,
                                                  block_level + 2 + rng() % 4)));
    const VerifyReport r = verify(1 + i % 3);
    ASSERT_TRUE(r.ok()) << "case " << i << ": " << r.problems[0];
    ASSERT_TRUE(r.mesh_checked);
    EXPECT_EQ(r.nodes, nodes_.size());
    EXPECT_EQ(r.elements, elements_.size());
    EXPECT_EQ(r.corners, 8 * elements_.size());
    uint64_t dangling = 0;
    for (const auto& n : nodes_) dangling += n.second != NodeKind::kAnchored;
    EXPECT_EQ(r.dangling, dangling);
    EXPECT_EQ(r.tables, 2u);
  }
}

// Both node checks, derived and independent, pass the reference meshes with
// the same counts.
TEST_F(VerifyTest, IndependentCheckAgreesOnReferenceMeshes) {
  for (int i = 0; i < 8; ++i) {
    std::mt19937_64 rng(100 + i);
    const uint32_t bx = 1 + rng() % 3, by = 1 + rng() % 3, bz = 1 + rng() % 2;
    ASSERT_NO_FATAL_FAILURE(build(random_balanced(100 + i, bx, by, bz, 2, 300 + rng() % 2000, 6)));
    const VerifyReport derived = verify(2), each = verify(2, true);
    ASSERT_TRUE(derived.ok()) << derived.problems[0];
    ASSERT_TRUE(each.ok()) << each.problems[0];
    EXPECT_EQ(each.nodes, derived.nodes);
    EXPECT_EQ(each.dangling, derived.dangling);
    EXPECT_EQ(each.corners, derived.corners);
    EXPECT_EQ(each.elements, derived.elements);
  }
}

TEST_F(VerifyTest, NamesAWrongKind) {
  ASSERT_NO_FATAL_FAILURE(build(random_balanced(3, 2, 1, 1, 1, 2000, 6)));
  for (uint64_t seed = 0; seed < 6; ++seed) {
    Nodes bad = nodes_;
    const size_t i = find_kind(seed % 2 ? NodeKind::kEdge : NodeKind::kFace, seed);
    bad[i].second = seed % 3 ? NodeKind::kAnchored : NodeKind::kFace;
    if (bad[i].second == nodes_[i].second) bad[i].second = NodeKind::kEdge;
    write_nodes(bad);
    expect_problem("node " + std::to_string(i) + " at ");
  }
}

// Problems all over the node table, more than the cap: every thread count
// names the same first 20, those of the lowest node ids.
TEST_F(VerifyTest, NamesTheSameFirstProblemsOnAnyThreadCount) {
  ASSERT_NO_FATAL_FAILURE(build(random_balanced(4, 2, 2, 1, 1, 3000, 6)));
  Nodes bad = nodes_;
  std::vector<size_t> changed;
  for (size_t i = 0; i < bad.size(); ++i) {
    if (bad[i].second == NodeKind::kAnchored || i % 7 != 0) continue;
    bad[i].second = NodeKind::kAnchored;
    changed.push_back(i);
  }
  ASSERT_GT(changed.size(), 40u);
  write_nodes(bad);
  const VerifyReport one = verify(1);
  ASSERT_EQ(one.problems.size(), 20u);
  EXPECT_NE(one.problems[0].find("node " + std::to_string(changed[0]) + " at "), std::string::npos)
      << one.problems[0];
  for (int threads : {2, 3, 5}) EXPECT_EQ(verify(threads).problems, one.problems) << threads;
}

TEST_F(VerifyTest, NamesAMissingNodeAndAnExtraOne) {
  ASSERT_NO_FATAL_FAILURE(build(random_balanced(5, 1, 2, 1, 1, 2000, 6)));
  // An anchored corner removed: some element corner is not a node (or some
  // dangling node lost an anchor).
  Nodes missing = nodes_;
  missing.erase(missing.begin() + find_kind(NodeKind::kAnchored, 17));
  write_nodes(missing);
  expect_problem("is not a node");
  // A node at the centre of an element.
  Nodes extra = nodes_;
  const Octant e = elements_[elements_.size() / 2];
  const uint32_t h = octant_edge(e) / 2;
  extra.emplace_back(node_key({e.x + h, e.y + h, e.z + h}), NodeKind::kAnchored);
  std::sort(extra.begin(), extra.end());
  write_nodes(extra);
  expect_problem("away from its corners and midpoints");
  // A dangling node whose anchor is itself dangling.
  Nodes wrong_anchor = nodes_;
  const size_t d = find_kind(NodeKind::kEdge, 3);
  Coord anchors[4];
  node_anchors(morton_decode(nodes_[d].first), NodeKind::kEdge, anchors);
  for (auto& n : wrong_anchor)
    if (n.first == node_key(anchors[0])) n.second = NodeKind::kFace;
  write_nodes(wrong_anchor);
  expect_problem("is not anchored");
}

TEST_F(VerifyTest, NamesAnUnbalancedOctree) {
  // Splitting one leaf into its 512 descendants three levels down puts them
  // beside neighbours at most one level finer than the leaf: a 2-level jump.
  // An import would drop the node table of the balanced mesh (it derives
  // from the octants), so the unbalanced octants are put beside it by hand,
  // as damage would: the node table is then stale too.
  std::vector<Octant> leaves = random_balanced(9, 1, 1, 1, 1, 200, 4);
  ASSERT_NO_FATAL_FAILURE(build(leaves));
  std::vector<Octant> split = {leaves[leaves.size() / 2]};
  leaves.erase(leaves.begin() + leaves.size() / 2);
  for (int level = 0; level < 3; ++level) {
    std::vector<Octant> finer;
    for (const Octant& o : split)
      for (int k = 0; k < 8; ++k) finer.push_back(octant_child(o, k));
    split.swap(finer);
  }
  leaves.insert(leaves.end(), split.begin(), split.end());
  const std::string text = db_ + ".unbalanced.txt";
  ASSERT_OK(write_octant_text(text, leaves, ""));
  ImportResult ir;
  const std::string other = db_ + ".unbalanced";
  ASSERT_OK(import_octants(other, text, ImportOptions{}, &ir));
  std::unique_ptr<Database> from, to;
  ASSERT_OK(Database::open(other, Database::Mode::kRead, false, &from));
  ASSERT_OK(Database::open(db_, Database::Mode::kWrite, false, &to));
  std::filesystem::copy_file(from->table_path(kOctantTable), db_ + "/octants-99.bt");
  ASSERT_OK(to->commit_exactly(
      {{kOctantTable, "octants-99.bt"},
       {kNodeTable, std::filesystem::path(to->table_path(kNodeTable)).filename()}}));
  to.reset();
  expect_problem("not 2:1 balanced");
}

TEST_F(VerifyTest, NamesADamagedPageAndWrongLevelCounts) {
  ASSERT_NO_FATAL_FAILURE(build(random_balanced(11, 2, 2, 1, 2, 3000, 6)));
  const std::string nodes_file = table_file(kNodeTable);
  {
    std::fstream f(nodes_file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(4096 + 4096 + 100);  // inside the second page after the header
    f.put('\x5a');
  }
  expect_problem("page");
  // Restore the nodes, then claim a wrong level histogram in the octants.
  write_nodes(nodes_);
  ASSERT_TRUE(verify().ok());
  ASSERT_NO_FATAL_FAILURE(claim_false_level_counts());
  expect_problem("metadata counts");
}

// Two tables damaged at once (a node page, the octants' level counts): the
// tables are checked on several threads, and reported as one thread would,
// the same problems and lines in the same order.
TEST_F(VerifyTest, TablesCheckedOnThreadsReportInTableOrder) {
  ASSERT_NO_FATAL_FAILURE(build(random_balanced(17, 2, 2, 1, 2, 3000, 6)));
  ASSERT_NO_FATAL_FAILURE(claim_false_level_counts());
  write_nodes(nodes_);  // (replacing the octants dropped the nodes derived from them)
  {
    std::fstream f(table_file(kNodeTable), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(4096 + 4096 + 100);  // inside the second page after the header
    f.put('\x5a');
  }
  auto run = [&](int threads, std::vector<std::string>* lines) {
    VerifyReport r;
    VerifyOptions o;
    o.memory = MemoryBudget(8 << 20);
    o.threads = threads;
    o.progress = [lines](const std::string& line) { lines->push_back(line); };
    EXPECT_OK(verify_database(db_, o, &r));
    return r;
  };
  std::vector<std::string> one_lines;
  const VerifyReport one = run(1, &one_lines);
  bool page = false, counts = false;
  for (const std::string& p : one.problems) {
    page = page || p.find("page") != std::string::npos;
    counts = counts || p.find("metadata counts") != std::string::npos;
  }
  EXPECT_TRUE(page && counts) << (one.problems.empty() ? "no problem" : one.problems[0]);
  ASSERT_GE(one.problems.size(), 2u);
  ASSERT_FALSE(one_lines.empty());  // the damaged table has no line: its problem says it
  for (int threads : {2, 3}) {
    std::vector<std::string> lines;
    const VerifyReport r = run(threads, &lines);
    EXPECT_EQ(r.problems, one.problems) << threads;
    EXPECT_EQ(lines, one_lines) << threads;
    EXPECT_EQ(r.tables, one.tables);
    EXPECT_EQ(r.records, one.records);
    EXPECT_EQ(r.pages, one.pages);
  }
}

TEST_F(VerifyTest, CommandExitStatus) {
  ASSERT_NO_FATAL_FAILURE(build(random_balanced(13, 1, 1, 1, 1, 500, 5)));
  uint64_t rss = 0;
  std::string out = bench::run_program({WEAVER_BINARY, "verify", db_}, &rss);
  EXPECT_NE(out.find("no problems"), std::string::npos) << out;
  Nodes bad = nodes_;
  bad[find_kind(NodeKind::kEdge, 1)].second = NodeKind::kAnchored;
  write_nodes(bad);
  const std::string cmd = std::string(WEAVER_BINARY) + " verify " + db_ + " >/dev/null 2>&1";
  EXPECT_EQ(WEXITSTATUS(std::system(cmd.c_str())), 1);
  EXPECT_EQ(WEXITSTATUS(std::system(
                (std::string(WEAVER_BINARY) + " verify " + db_ + " --storage-only >/dev/null 2>&1")
                    .c_str())),
            0);
  EXPECT_EQ(
      WEXITSTATUS(std::system((std::string(WEAVER_BINARY) + " verify >/dev/null 2>&1").c_str())),
      2);
}

}  // namespace
}  // namespace weaver
