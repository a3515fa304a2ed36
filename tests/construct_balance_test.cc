// The balanced construct (construct/subtree_balance.h) against its slow,
// obviously correct reference: the descent's own leaves written unbalanced,
// then balanced by `weaver balance`'s out-of-core level-by-level closure
// (closure.h: none of the windows' ripple, which the construct shares), and
// on the small cases by tests/reference's balance as well.  The two tables
// must agree byte for byte (same leaves, same materials, same pages) on
// models with smooth and with extreme grading, cube and non-cube domains,
// domains rounded up to blocks, models with and without Q, at 1 to 3
// threads and at budgets so small that subtrees overflow their cap.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "balance/balance.h"
#include "construct/construct.h"
#include "db/database.h"
#include "db/octant_table.h"
#include "model/grid_model.h"
#include "modeldb/open_model.h"
#include "reference/reference_mesh.h"
#include "test_mesh.h"
#include "test_util.h"

namespace weaver {
namespace {

// A model with deep grading at random places: rock (Vs 3000 m/s) on a
// coarse grid with a few grid points turned soft (Vs down to 40 m/s), so
// leaves of 3 km meet leaves of a few tens of metres (the basin's own case
// of soft inclusions in rock, at small size).
std::string graded_grid(const testing::TempDir& dir, int seed) {
  GridSpec s;
  s.nx = 9, s.ny = 7, s.nz = 5;
  s.dx = 2500, s.dy = 2500, s.dz = 2500;
  std::vector<Material> values(size_t(s.nx) * s.ny * s.nz);
  for (Material& m : values) m = {5200, 3000, 2600, 0, 0};
  std::mt19937 rng(seed);
  for (int i = 0; i < 3; ++i) {
    Material& m = values[rng() % values.size()];
    m.vs = float(40 + rng() % 400);
    m.vp = 2 * m.vs;
    m.rho = 1800;
  }
  const std::string path = dir.file("graded-" + std::to_string(seed) + ".grid");
  EXPECT_OK(write_grid_model(path, s, values));
  return path;
}

struct ModelCase {
  std::string name;
  ConstructOptions options;
  bool splits = true;    // the balance has leaves to split (loh1's descent is balanced)
  bool rounded = false;  // the domain is rounded up to blocks
};

// The leaves of db's octant table, in key order.
std::vector<Octant> leaves_of(const std::string& db_dir) {
  std::vector<Octant> out;
  std::unique_ptr<Database> db;
  EXPECT_OK(Database::open(db_dir, Database::Mode::kRead, false, &db));
  std::unique_ptr<BTree> t;
  EXPECT_OK(db->open_table(kOctantTable, 1 << 20, &t));
  BTreeCursor c;
  EXPECT_OK(t->seek_cursor(0, &c));
  while (c.valid()) {
    out.push_back(octant_from_key(c.key()));
    EXPECT_OK(c.next());
  }
  return out;
}

std::vector<ModelCase> cases(const testing::TempDir& dir) {
  std::vector<ModelCase> out;
  auto add = [&](std::string name, const std::string& model, double freq,
                 std::array<double, 3> domain) {
    ModelCase c{std::move(name), ConstructOptions{}};
    c.options.model = model;
    c.options.freq = freq;
    c.options.domain_m = domain;
    out.push_back(c);
    return &out.back().options;
  };
  add("basin", "basin", testing::small_scale() ? 0.1 : 0.2, {100000, 100000, 37500});
  add("basin, 40 x 32 x 15 blocks", "basin", 0.12, {100000, 80000, 37500});
  // Extents with no common block: the domain is rounded up, to 234 m blocks.
  add("basin, domain rounded up", "basin", 0.12, {30001, 3001, 1501});
  out.back().rounded = true;
  add("loh1", "loh1", 0.6, {20000, 20000, 10000});
  out.back().splits = false;
  ConstructOptions* o = add("basin, vs floor and levels", "basin", 0.3, {50000, 50000, 25000});
  o->vs_min = 400;
  o->min_level = 6;
  o->max_level = 11;
  for (int seed : {1, 2, 3}) {
    o = add("graded grid " + std::to_string(seed), "grid", 0.3, {20000, 15000, 10000});
    o->grid_file = graded_grid(dir, seed);
    // The grid's trilinear ramps grade the descent's own leaves 2:1 at this
    // frequency: nothing to split (ModelDatabasesAgreeToo's grid splits).
    out.back().splits = false;
  }
  return out;
}

// What a case's construct then balance wrote (the table at `path`), built
// once for all the thread counts and budgets a case is tried at: they do not
// change it, and building it again for each was half this file's time.
struct Reference {
  std::string path;
  ConstructResult unbalanced;
  BalanceResult balanced;
  std::vector<Octant> leaves;  // tests/reference's balance (small cases only)
};

void build_reference(const ModelCase& c, const std::string& path, Reference* ref) {
  ref->path = path;
  ConstructOptions o = c.options;
  o.balanced = false;
  ConstructPlan plan;
  ASSERT_OK(construct_octree(path, o, &plan, &ref->unbalanced));
  EXPECT_EQ(plan.rounded_up, c.rounded);
  if (ref->unbalanced.elements <= 20000) ref->leaves = reference::balance(leaves_of(path));
  BalanceOptions closure;
  closure.algorithm = BalanceOptions::Algorithm::kClosure;
  // A model database is named by its identity: balance is told where it is.
  if (o.model.rfind("db:", 0) == 0) closure.model_dirs.push_back(o.model.substr(3));
  ASSERT_OK(balance_octree(path, closure, &ref->balanced));
  EXPECT_FALSE(ref->balanced.by_windows);
}

// The case built balanced in one pass, checked against the reference's
// counts and (small cases) leaves; the caller compares the tables' bytes.
// subtree_leaves, subtree_pool: the subtrees' rooms and pool (0: as the
// budget allows).
void build_balanced(const ModelCase& c, const Reference& ref, const std::string& balanced,
                    int threads, uint64_t budget, ConstructResult* r, uint64_t subtree_leaves = 0,
                    uint64_t subtree_pool = 0) {
  ConstructOptions o = c.options;
  o.balanced = true;
  o.threads = threads;
  o.subtree_leaves = subtree_leaves;
  o.subtree_pool = subtree_pool;
  o.memory = MemoryBudget(budget);
  ConstructPlan plan;
  ASSERT_OK(construct_octree(balanced, o, &plan, r));
  const BalanceResult& br = ref.balanced;
  EXPECT_EQ(r->descended, ref.unbalanced.elements);
  EXPECT_EQ(r->elements, br.output_leaves);
  EXPECT_EQ(r->levels, br.levels);
  EXPECT_EQ(r->elements - r->descended, br.output_leaves - br.input_leaves);
  EXPECT_EQ(r->elements > r->descended, c.splits);
  if (!ref.leaves.empty()) {
    EXPECT_TRUE(leaves_of(balanced) == ref.leaves) << "against tests/reference";
  }
}

TEST(BalancedConstruct, WritesWhatConstructThenBalanceWriteByteForByte) {
  testing::TempDir dir;
  const std::vector<int> threads =
      testing::small_scale() ? std::vector<int>{1, 3} : std::vector<int>{1, 2, 3};
  uint64_t overflowed = 0, against_reference = 0;
  for (const ModelCase& c : cases(dir)) {
    SCOPED_TRACE(c.name);
    Reference ref;
    ASSERT_NO_FATAL_FAILURE(build_reference(c, dir.file("ref"), &ref));
    for (int t : threads) {
      for (uint64_t budget : {MemoryBudget::kDefaultBytes, MemoryBudget::kMinBytes}) {
        if (budget == MemoryBudget::kMinBytes && t == 2) continue;
        SCOPED_TRACE(std::to_string(t) + " threads, budget " + std::to_string(budget));
        const std::string got = dir.file("got");
        ConstructResult r;
        ASSERT_NO_FATAL_FAILURE(build_balanced(c, ref, got, t, budget, &r));
        ASSERT_EQ(testing::table_bytes(got), testing::table_bytes(ref.path));
        // At the least budget the subtrees overflow their cap (header).
        if (budget == MemoryBudget::kMinBytes) overflowed += r.subtrees_over > 0;
        against_reference += !ref.leaves.empty();
        BalanceOptions check;
        check.check_only = true;
        BalanceResult verdict;
        ASSERT_OK(balance_octree(got, check, &verdict));
        EXPECT_TRUE(verdict.balanced) << verdict.violation;
        std::filesystem::remove_all(got);
      }
    }
    std::filesystem::remove_all(ref.path);
  }
  // Subtrees overflowed their cap in some of the least budget's runs, and
  // some cases were small enough for tests/reference.
  EXPECT_GT(overflowed, 0u);
  EXPECT_GT(against_reference, 0u);
}

// Subtrees that take leaves from a shared pool past their own rooms
// (construct/leaf_room.h) write the same table, and pass their rooms less
// often than fixed rooms of the same size: at rooms of 64 leaves, with a
// pool and without (where subtrees do take from it), and at the budget
// that pools (1G: the pooled rooms' set-up, though these small cases'
// subtrees stay within their own rooms of 256K leaves there).
TEST(BalancedConstruct, APoolOfLeavesChangesNothingButTheSubtreesVisitedAgain) {
  testing::TempDir dir;
  uint64_t fewer = 0;
  for (const ModelCase& c : cases(dir)) {
    SCOPED_TRACE(c.name);
    Reference ref;
    ASSERT_NO_FATAL_FAILURE(build_reference(c, dir.file("ref"), &ref));
    const std::string expected = testing::table_bytes(ref.path);
    ConstructResult fixed, pooled, budgeted;
    for (int t : testing::small_scale() ? std::vector<int>{2} : std::vector<int>{1, 2}) {
      SCOPED_TRACE(std::to_string(t) + " threads");
      const std::string got = dir.file("got");
      ASSERT_NO_FATAL_FAILURE(
          build_balanced(c, ref, got, t, MemoryBudget::kDefaultBytes, &fixed, 64, 0));
      ASSERT_EQ(testing::table_bytes(got), expected);
      std::filesystem::remove_all(got);
      ASSERT_NO_FATAL_FAILURE(
          build_balanced(c, ref, got, t, MemoryBudget::kDefaultBytes, &pooled, 64, 4096));
      ASSERT_EQ(testing::table_bytes(got), expected);
      std::filesystem::remove_all(got);
      EXPECT_LE(pooled.subtrees_over, fixed.subtrees_over);
      fewer += pooled.subtrees_over < fixed.subtrees_over;
      ASSERT_NO_FATAL_FAILURE(build_balanced(c, ref, got, t, 1ull << 30, &budgeted));
      ASSERT_EQ(testing::table_bytes(got), expected);
      std::filesystem::remove_all(got);
    }
    std::filesystem::remove_all(ref.path);
  }
  // Some subtrees past their own room of 64 finished in the pool's.
  EXPECT_GT(fewer, 0u);
}

// Model databases (what `weaver construct --model grid:FILE` or
// `layers:FILE` import): a graded grid, whose new leaves read their
// material from the model database, and a layered table with Q (20-byte
// records; the descent grades its layers itself, so nothing splits there).
TEST(BalancedConstruct, ModelDatabasesAgreeToo) {
  testing::TempDir dir;
  // A thin soft layer over rock: 100 m leaves on 1.6 km ones.
  std::ofstream(dir.file("layers.txt")) << "0 400 100 1800 20 10\n"
                                           "150 3000 1700 2300 200 100\n"
                                           "2600 5000 2900 2600 400 200\n";
  const std::string sources[] = {"grid:" + graded_grid(dir, 4), "layers:" + dir.file("layers.txt")};
  for (const std::string& source : sources) {
    ModelCase c{source, ConstructOptions{}};
    c.splits = source.rfind("grid", 0) == 0;  // the layers' descent grades itself
    c.options.freq = 0.1;
    c.options.domain_m = {20000, 15000, 10000};
    c.options.model = source;
    ModelImportResult ir;
    const std::string model_db = dir.file("model-" + source.substr(0, 4));
    ASSERT_OK(import_model_source(model_db, MemoryBudget(), &c.options.model, &ir));
    Reference ref;
    ASSERT_NO_FATAL_FAILURE(build_reference(c, dir.file("ref-" + source.substr(0, 4)), &ref));
    // Two threads at the default budget pool their rooms (a level coarser
    // subtrees); three do not.
    for (int t : {1, 2, 3}) {
      SCOPED_TRACE(source + ", " + std::to_string(t) + " threads");
      const std::string got = dir.file("got-" + std::to_string(t) + source.substr(0, 4));
      ConstructResult r;
      ASSERT_NO_FATAL_FAILURE(build_balanced(c, ref, got, t, MemoryBudget::kDefaultBytes, &r));
      ASSERT_EQ(testing::table_bytes(got), testing::table_bytes(ref.path));
    }
  }
}

// A subtree whose box holds more model octants than its reader's region
// (modeldb/model_region.h) has room for is visited as its eight children,
// each box an eighth, not answered point by point from the model table:
// the same table.  A grid of 48 x 48 x 24 distinct values at 500 m is
// 55K model octants; at the least budget a region holds 4096, fewer than
// its subtrees' boxes, and rooms of 1M leaves never overflow, so every
// subtree visited again was the region's.
TEST(BalancedConstruct, ASubtreeItsModelRegionCannotHoldIsVisitedAsItsChildren) {
  testing::TempDir dir;
  GridSpec s;
  s.nx = 48, s.ny = 48, s.nz = 24;
  s.dx = s.dy = s.dz = 500;
  std::vector<Material> values(size_t(s.nx) * s.ny * s.nz);
  std::mt19937 rng(11);
  for (Material& m : values) {
    m.vs = float(1000 + rng() % 2000);
    m.vp = 1.8f * m.vs;
    m.rho = 2000;
  }
  const std::string grid = dir.file("dense.grid");
  ASSERT_OK(write_grid_model(grid, s, values));
  ModelCase c{"dense grid", ConstructOptions{}};
  c.splits = false;  // Vs within 3x: the descent's leaves are graded 2:1
  c.options.freq = 0.2;
  c.options.domain_m = {24000, 24000, 12000};
  c.options.model = "grid:" + grid;
  ModelImportResult ir;
  ASSERT_OK(import_model_source(dir.file("model"), MemoryBudget(), &c.options.model, &ir));
  ASSERT_GT(ir.octants, 4096u * 8);
  // At 0.2 Hz the subtrees split; at 0.008 Hz each block of 12 km is one
  // leaf, whose box holds 13.8K model octants: its children are no part of
  // the octree, and it stays whole.
  for (const double freq : {0.2, 0.008}) {
    c.options.freq = freq;
    Reference ref;
    ASSERT_NO_FATAL_FAILURE(build_reference(c, dir.file("ref"), &ref));
    for (int t : {1, 2}) {
      SCOPED_TRACE(std::to_string(freq) + " Hz, " + std::to_string(t) + " threads");
      const std::string got = dir.file("got-" + std::to_string(t));
      ConstructResult r;
      ASSERT_NO_FATAL_FAILURE(
          build_balanced(c, ref, got, t, MemoryBudget::kMinBytes, &r, uint64_t{1} << 20, 0));
      ASSERT_EQ(testing::table_bytes(got), testing::table_bytes(ref.path));
      EXPECT_EQ(r.subtrees_over > 0, freq > 0.1);
      std::filesystem::remove_all(got);
    }
    std::filesystem::remove_all(ref.path);
  }
}

}  // namespace
}  // namespace weaver
