// weaver balance against the brute-force reference balancer: the same leaf
// set, on hundreds of random unbalanced octrees, including non-cube domains
// and tiny budgets that push every sort out of core.
#include "balance/balance.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <random>

#include "balance/window_edges.h"
#include "construct/construct.h"
#include "db/database.h"
#include "gen/octree_gen.h"
#include "import/import.h"
#include "import/octant_text.h"
#include "model/velocity_model.h"
#include "reference/reference_mesh.h"
#include "sample_octrees.h"
#include "test_mesh.h"
#include "test_octrees.h"
#include "test_util.h"
#include "util/local_ripple.h"
#include "util/parent_asks.h"

namespace weaver {
namespace {

// The message names two input leaves, face or edge neighbours, two or more
// levels apart.
void expect_names_a_violation(const std::string& violation, const std::vector<Octant>& leaves) {
  std::vector<Octant> named;
  size_t pos = 0;
  while ((pos = violation.find('(', pos)) != std::string::npos) {
    unsigned x, y, z, l;
    ASSERT_EQ(std::sscanf(violation.c_str() + pos, "(%u %u %u %u)", &x, &y, &z, &l), 4);
    named.push_back({x, y, z, uint8_t(l)});
    ++pos;
  }
  ASSERT_EQ(named.size(), 2u) << violation;
  EXPECT_TRUE(reference::face_or_edge_adjacent(named[0], named[1])) << violation;
  EXPECT_GE(std::abs(int(named[0].level) - int(named[1].level)), 2) << violation;
  EXPECT_NE(std::find(leaves.begin(), leaves.end(), named[0]), leaves.end()) << violation;
  EXPECT_NE(std::find(leaves.begin(), leaves.end(), named[1]), leaves.end()) << violation;
}

// The tables of what a parent's leaves ask for, against geometry: child c
// asks for neighbour d of its parent iff they share a face or an edge.
TEST(ParentAsks, ChildrenAskForTheNeighboursTheyTouch) {
  const Octant parent{1u << 18, 1u << 18, 1u << 18, 2};  // inside the root on every side
  for (unsigned children = 0; children < 256; ++children) {
    uint32_t want = 0;
    for (size_t i = 0; i < kFaceAndEdgeDirections.size(); ++i) {
      Octant n;
      ASSERT_TRUE(octant_neighbour(parent, kFaceAndEdgeDirections[i], &n));
      uint8_t touching = 0;
      for (int c = 0; c < 8; ++c) {
        if (reference::face_or_edge_adjacent(octant_child(parent, c), n)) touching |= 1u << c;
      }
      if (children == 255) {
        ASSERT_EQ(parent_asks::kTouching[i], touching) << i;
      }
      if (children & touching) want |= 1u << i;
    }
    ASSERT_EQ(parent_asks::kTouchedBy[children], want) << children;
  }
  EXPECT_TRUE(parent_asks::is_children_tag(parent_asks::children_tag(0x5a)));
  EXPECT_EQ(parent_asks::children_of(parent_asks::children_tag(0x5a)), 0x5au);
  EXPECT_FALSE(octant_key_is_valid(parent_asks::children_tag(0x5a)));
}

// Up to 300 random leaves in a domain of up to 4 x 4 x 4 blocks, as deep
// as 9 levels below them.
GenOptions random_small_octree(std::mt19937_64& rng) {
  GenOptions g;
  g.seed = rng();
  g.block_level = static_cast<int>(rng() % 3);
  const uint32_t per_axis = 1u << g.block_level;
  for (int a = 0; a < 3; ++a) g.blocks[a] = 1 + rng() % per_axis;
  g.leaves = 10 + rng() % 300;
  g.max_level = g.block_level + 1 + static_cast<int>(rng() % 9);
  return g;
}

// A random octree of about `leaves` leaves, none finer than max_level
// (empty if generating it failed).
std::vector<Octant> random_octree(uint64_t seed, uint64_t leaves, int max_level) {
  GenOptions g;
  g.seed = seed;
  g.leaves = leaves;
  g.max_level = max_level;
  std::vector<Octant> out;
  if (!generate_octree(g, &out).ok()) out.clear();
  return out;
}

class BalanceTest : public ::testing::Test {
 protected:
  std::string import(const std::vector<Octant>& leaves) {
    const std::string db = dir_.file("db" + std::to_string(count_++));
    EXPECT_OK(write_octant_text(db + ".txt", leaves, ""));
    ImportResult r;
    EXPECT_OK(import_octants(db, db + ".txt", ImportOptions{}, &r));
    return db;
  }
  std::vector<Octant> table(const std::string& db) {
    std::vector<Octant> out;
    for (uint64_t key : testing::octant_table_keys(db)) out.push_back(octant_from_key(key));
    return out;
  }
  // Checks, balances and checks again one octree, against the reference;
  // returns whether it needed refinement.
  bool balances_as_the_reference(const std::vector<Octant>& leaves, const BalanceOptions& o,
                                 BalanceResult* result = nullptr) {
    const std::vector<Octant> want = reference::balance(leaves);
    const std::string db = import(leaves);
    BalanceOptions check;
    check.check_only = true;
    BalanceResult cr;
    EXPECT_OK(balance_octree(db, check, &cr));
    EXPECT_EQ(cr.balanced, want == leaves) << cr.violation;
    if (!cr.balanced) expect_names_a_violation(cr.violation, leaves);
    BalanceResult r;
    EXPECT_OK(balance_octree(db, o, &r));
    EXPECT_EQ(table(db), want);
    EXPECT_EQ(r.output_leaves, want.size());
    EXPECT_EQ(r.input_leaves, leaves.size());
    BalanceResult after;
    EXPECT_OK(balance_octree(db, check, &after));
    EXPECT_TRUE(after.balanced) << after.violation;
    if (result != nullptr) *result = r;
    return want != leaves;
  }
  testing::TempDir dir_;
  int count_ = 0;
};

// Windows of every length, cut in two where they outgrow a tiny memory,
// each against its insulation layer, or given up for the closure where a
// layer outweighs its window: the reference's table every time.
TEST_F(BalanceTest, WindowsOfAnyLengthMatchTheReference) {
  std::mt19937_64 rng(11);
  const int cases = static_cast<int>(testing::scaled(200, 30));
  int gave_up = 0, kept = 0, one_window = 0;
  for (int t = 0; t < cases; ++t) {
    std::vector<Octant> leaves;
    ASSERT_OK(generate_octree(random_small_octree(rng), &leaves));
    BalanceOptions o;
    o.window_leaves = 1 + rng() % 64;
    o.threads = 1 + t % 3;
    // Auto on several threads gives up windows whose layer outweighs them,
    // for the closure: the same table.
    o.algorithm =
        t % 5 == 4 ? BalanceOptions::Algorithm::kAuto : BalanceOptions::Algorithm::kWindows;
    if (t % 4 == 3) o.memory = MemoryBudget(64 << 10);
    SCOPED_TRACE("case " + std::to_string(t) + ": " + std::to_string(leaves.size()) +
                 " leaves, windows of " + std::to_string(o.window_leaves) + ", " +
                 std::to_string(o.threads) + " threads");
    BalanceResult r;
    balances_as_the_reference(leaves, o, &r);
    ASSERT_FALSE(HasFailure());
    if (o.algorithm == BalanceOptions::Algorithm::kWindows) {
      // Windows that do not fit in a tiny memory, even as one leaf, fall back.
      if (t % 4 != 3) {
        EXPECT_TRUE(r.by_windows);
      }
    } else {
      // Windows on several threads given up, for one window of every leaf.
      const bool one = r.by_windows && o.threads > 1 && r.windows == 1 &&
                       leaves.size() > o.window_leaves && r.layer_leaves == 0;
      gave_up += !r.by_windows || one;
      kept += r.by_windows && !one;
      one_window += one;
    }
  }
  // Random refinement has coarse leaves among fine ones: windows are given
  // up and kept, and one window follows the windows given up.
  EXPECT_GT(gave_up, 0);
  EXPECT_GT(kept, 0);
  EXPECT_GT(one_window, 0);
}

TEST_F(BalanceTest, MatchesReferenceOnRandomUnbalancedOctrees) {
  std::mt19937_64 rng(5);
  const int cases = static_cast<int>(testing::scaled(250, 40));
  int unbalanced = 0;
  for (int t = 0; t < cases; ++t) {
    std::vector<Octant> leaves;
    ASSERT_OK(generate_octree(random_small_octree(rng), &leaves));
    SCOPED_TRACE("case " + std::to_string(t) + ": " + std::to_string(leaves.size()) + " leaves");
    BalanceOptions o;
    o.memory = MemoryBudget((t % 3 == 0) ? (64 << 10) : (64 << 20));  // tiny: sorts spill
    if (t % 2 == 1) {  // every chunk of parents shared among threads
      o.threads = 2 + t % 3;
      o.parallel_chunk = 1;
    }
    o.algorithm = t % 4 < 2
                      ? BalanceOptions::Algorithm::kWindows  // else the closure (their fallback)
                      : BalanceOptions::Algorithm::kClosure;
    unbalanced += balances_as_the_reference(leaves, o);
    ASSERT_FALSE(HasFailure());
  }
  EXPECT_GT(unbalanced, cases / 2);  // the cases exercise real refinement
}

// Domains whose boundary is finer than the domain map's cells (blocks of
// levels 5 and 6; the tiny budget makes the map level 4): the candidates
// in cells the leaves cover in part are asked of the table.
TEST_F(BalanceTest, MatchesReferenceOnDomainsFinerThanTheDomainMap) {
  std::mt19937_64 rng(11);
  const int cases = static_cast<int>(testing::scaled(60, 15));
  for (int t = 0; t < cases; ++t) {
    GenOptions g;
    g.seed = rng();
    g.block_level = 5 + static_cast<int>(rng() % 2);
    for (int a = 0; a < 3; ++a) g.blocks[a] = 1 + rng() % 5;
    g.leaves = 150 + rng() % 200;
    g.max_level = g.block_level + 2 + static_cast<int>(rng() % 4);
    std::vector<Octant> leaves;
    ASSERT_OK(generate_octree(g, &leaves));
    SCOPED_TRACE("case " + std::to_string(t) + ": " + std::to_string(leaves.size()) + " leaves");
    BalanceOptions o;
    o.memory = MemoryBudget(64 << 10);
    o.threads = 1 + t % 2;
    o.parallel_chunk = 1;
    o.algorithm = BalanceOptions::Algorithm::kClosure;  // its domain map is what this tries
    balances_as_the_reference(leaves, o);
    ASSERT_FALSE(HasFailure());
  }
}

// Holes as fine as the leaves (an imported octree need not fill its
// parents): a leaf whose siblings are missing asks only for the neighbours
// it touches, so the result is still the minimal balanced refinement, and
// --check calls a tree balanced exactly when the reference leaves it alone.
TEST_F(BalanceTest, MatchesReferenceWhereLeavesDoNotFillTheirParents) {
  std::mt19937_64 rng(17);
  const int cases = static_cast<int>(testing::scaled(200, 40));
  int unbalanced = 0;
  for (int t = 0; t < cases; ++t) {
    const uint64_t seed = rng(), count = 30 + rng() % 300;
    const int max_level = 3 + static_cast<int>(rng() % 7);
    const std::vector<Octant> leaves =
        testing::random_holed(seed, count, max_level, 0.5 + 0.1 * double(rng() % 5));
    if (leaves.empty()) continue;
    SCOPED_TRACE("case " + std::to_string(t) + ": " + std::to_string(leaves.size()) + " leaves");
    BalanceOptions o;
    o.memory = MemoryBudget((t % 2 == 0) ? (64 << 10) : (64 << 20));  // the map coarse or fine
    o.threads = 1 + t % 3;
    o.parallel_chunk = 1;
    o.algorithm =
        t % 4 < 2 ? BalanceOptions::Algorithm::kWindows : BalanceOptions::Algorithm::kClosure;
    unbalanced += balances_as_the_reference(leaves, o);
    ASSERT_FALSE(HasFailure());
  }
  EXPECT_GT(unbalanced, cases / 3);
}

// The basin's octree and a random one, balanced on 1 to 3 threads, in
// windows as long as the memory allows or a few thousand leaves, or by the
// closure with chunks shared among the threads from the default size down
// to a handful of parents, and budgets that spill the sorters or not: the
// same table, byte for byte, and balanced.
TEST(BalanceThreads, AnyThreadCountWritesTheSameTable) {
  testing::TempDir dir;
  ConstructOptions co;
  co.model = "basin";
  co.balanced = false;
  co.freq = testing::small_scale() ? 0.1 : 0.2;
  ConstructPlan plan;
  ConstructResult cr;
  ASSERT_OK(construct_octree(dir.file("basin"), co, &plan, &cr));
  const std::vector<Octant> leaves = random_octree(3, testing::scaled(200000, 40000), 9);
  ASSERT_FALSE(leaves.empty());
  ASSERT_OK(write_octant_text(dir.file("random.txt"), leaves, ""));
  ImportResult ir;
  ASSERT_OK(import_octants(dir.file("random"), dir.file("random.txt"), ImportOptions{}, &ir));
  using A = BalanceOptions::Algorithm;
  struct Run {
    int threads;
    size_t chunk;
    uint64_t budget;
    A algorithm;
    uint64_t window_leaves;
  };
  // Under the sanitizers: one thread against three, sharing small chunks
  // with a spilling budget.
  const std::vector<Run> runs =
      testing::small_scale() ? std::vector<Run>{{1, size_t{1} << 15, 64 << 20, A::kWindows, 0},
                                                {3, 64, 256 << 10, A::kClosure, 0},
                                                {3, 64, 256 << 10, A::kWindows, 3000},
                                                {2, 64, 64 << 20, A::kAuto, 0}}
                             : std::vector<Run>{{1, size_t{1} << 15, 64 << 20, A::kWindows, 0},
                                                {2, size_t{1} << 15, 64 << 20, A::kWindows, 0},
                                                {3, 1000, 64 << 20, A::kClosure, 0},
                                                {2, 64, 256 << 10, A::kWindows, 5000},
                                                {2, 64, 256 << 10, A::kClosure, 0},
                                                {1, 64, 256 << 10, A::kClosure, 0},
                                                {2, 64, 256 << 20, A::kAuto, 0},
                                                {3, 64, 256 << 20, A::kAuto, 0}};
  for (const char* name : {"basin", "random"}) {
    std::string first;
    for (const Run& run : runs) {
      SCOPED_TRACE(std::string(name) + ", " + std::to_string(run.threads) + " threads, chunk " +
                   std::to_string(run.chunk) + ", budget " + std::to_string(run.budget) +
                   ", algorithm " + std::to_string(static_cast<int>(run.algorithm)));
      const std::string db = dir.file(std::string(name) + "-" + std::to_string(&run - &runs[0]));
      std::filesystem::copy(dir.file(name), db);
      BalanceOptions o;
      o.threads = run.threads;
      o.parallel_chunk = run.chunk;
      o.memory = MemoryBudget(run.budget);
      o.algorithm = run.algorithm;
      o.window_leaves = run.window_leaves;
      BalanceResult r;
      ASSERT_OK(balance_octree(db, o, &r));
      EXPECT_GT(r.split, 0u);
      // Auto on several threads takes one window of the random octree,
      // whose levels' asks and created octants its threads share.
      if (run.algorithm == A::kAuto && std::string(name) == "random") {
        EXPECT_TRUE(r.by_windows && r.windows == 1 && r.layer_leaves == 0);
      }
      const std::string bytes = testing::table_bytes(db);
      if (first.empty()) first = bytes;
      ASSERT_EQ(bytes, first);
      BalanceOptions check = o;
      check.check_only = true;
      BalanceResult after;
      ASSERT_OK(balance_octree(db, check, &after));
      EXPECT_TRUE(after.balanced) << after.violation;
    }
  }
}

// The window's edge test: a leaf that the holding octant's neighbours
// excuse (none of those it can reach leaves the window) has every
// neighbour inside the window or outside the root, checked one by one on
// random leaves and random runs of keys.
TEST(WindowEdges, ExcusedLeavesHaveEveryNeighbourInsideTheWindow) {
  std::mt19937_64 rng(23);
  int excused = 0, asked = 0;
  for (int t = 0; t < 20000; ++t) {
    const int level = 1 + static_cast<int>(rng() % 8);
    const uint32_t cells = 1u << level, edge = octant_edge(level);
    const Octant leaf{uint32_t(rng() % cells) * edge, uint32_t(rng() % cells) * edge,
                      uint32_t(rng() % cells) * edge, uint8_t(level)};
    const uint64_t key = octant_key(leaf);
    // A window around the leaf: up to a few subtrees of a coarser level
    // on either side of it.
    const int coarser = static_cast<int>(rng() % level);
    // (A subtree of that level spans 2^(3 (20 - level) + 4) keys; the root's, all 2^64.)
    const uint64_t span = uint64_t{1} << std::min(62, 3 * (kMaxLevel - coarser) + 4);
    const uint64_t end = octant_key_subtree_end(key);
    const uint64_t from = key - std::min<uint64_t>(key, rng() % span);
    const uint64_t to = end + std::min<uint64_t>(UINT64_MAX - end, rng() % span);
    uint64_t anc = key;
    while (octant_key_level(anc) > 0 && window_edges::within(octant_key_parent(anc), from, to)) {
      anc = octant_key_parent(anc);
    }
    const unsigned sides = window_edges::touched_sides(key, octant_key_level(anc));
    const uint32_t leaving = window_edges::neighbours_leaving(anc, from, to);
    bool all_inside = true;
    for (const Direction& d : kAllDirections) {
      uint64_t nb = 0;
      if (octant_key_neighbour(key, d, &nb) && !window_edges::within(nb, from, to)) {
        all_inside = false;
      }
    }
    if ((window_edges::kReachable[sides] & leaving) == 0) {
      ++excused;
      ASSERT_TRUE(all_inside) << describe_octant(leaf) << " in [" << from << ", " << to << ")";
    } else {
      ++asked;
    }
  }
  EXPECT_GT(excused, 1000);  // both ways are tried
  EXPECT_GT(asked, 1000);
}

// One window's ripple on two threads (each taking half of a level's asks,
// and half of the final merge) finds the octants one thread finds, on a
// random octree large enough for its levels to be shared.
TEST(LocalRippleThreads, TwoThreadsCreateWhatOneCreates) {
  const std::vector<Octant> leaves = random_octree(9, testing::scaled(200000, 60000), 10);
  std::vector<uint64_t> keys;
  for (const Octant& o : leaves) keys.push_back(octant_key(o));
  std::sort(keys.begin(), keys.end());
  std::vector<uint64_t> one, two;
  LocalRipple single(1), shared(2);
  ASSERT_TRUE(single.run(keys, &one));
  ASSERT_TRUE(shared.run(keys, &two));
  EXPECT_GT(one.size(), keys.size() / 2);  // real work, past the threads' threshold
  EXPECT_TRUE(std::is_sorted(one.begin(), one.end()));
  EXPECT_TRUE(std::adjacent_find(one.begin(), one.end()) == one.end());
  EXPECT_EQ(two, one);
  // Run again, the same object: nothing carried over.
  ASSERT_TRUE(shared.run(keys, &two));
  EXPECT_EQ(two, one);
}

// A leaf made by a split takes the model's vp, vs and rho at its centre
// (the refinement leaves this to its appender's thread); every other field,
// and every leaf that was not split, keeps its bytes.
TEST_F(BalanceTest, NewLeavesTakeTheModelsMaterialAtTheirCentre) {
  ConstructOptions co;
  co.model = "basin";
  co.balanced = false;
  co.freq = 0.1;
  ConstructPlan plan;
  ConstructResult cr;
  const std::string db = dir_.file("basin");
  ASSERT_OK(construct_octree(db, co, &plan, &cr));
  auto read_all = [&](std::map<uint64_t, std::vector<std::byte>>* out, TableOptions* opt) {
    std::unique_ptr<Database> d;
    std::unique_ptr<BTree> t;
    ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &d));
    ASSERT_OK(d->open_table(kOctantTable, 1 << 20, &t));
    *opt = t->options();
    BTreeCursor c;
    ASSERT_OK(t->seek_cursor(0, &c));
    while (c.valid()) {
      (*out)[c.key()].assign(c.payload(), c.payload() + t->payload_size());
      ASSERT_OK(c.next());
    }
  };
  std::map<uint64_t, std::vector<std::byte>> before, after;
  TableOptions opt;
  read_all(&before, &opt);
  BalanceResult r;
  ASSERT_OK(balance_octree(db, BalanceOptions{}, &r));
  ASSERT_GT(r.split, 0u);
  read_all(&after, &opt);
  std::unique_ptr<VelocityModel> model;
  ASSERT_OK(make_model("basin", "", &model));
  Units u;
  units_from_metadata(opt.metadata, &u);
  const Field *vp = opt.schema.find("vp"), *vs = opt.schema.find("vs"),
              *rho = opt.schema.find("rho");
  ASSERT_TRUE(vp != nullptr && vs != nullptr && rho != nullptr);
  uint64_t made = 0;
  for (const auto& [key, payload] : after) {
    const auto old = before.find(key);
    if (old != before.end()) {
      ASSERT_EQ(payload, old->second);
      continue;
    }
    ++made;
    const Octant o = octant_from_key(key);
    const double h = octant_edge(o) * u.tick_m / 2;
    const Material m = model->at(o.x * u.tick_m + h, o.y * u.tick_m + h, o.z * u.tick_m + h);
    ASSERT_EQ(RecordSchema::get_double(payload.data(), *vp), m.vp);
    ASSERT_EQ(RecordSchema::get_double(payload.data(), *vs), m.vs);
    ASSERT_EQ(RecordSchema::get_double(payload.data(), *rho), m.rho);
  }
  EXPECT_EQ(made + before.size() - r.split, after.size());
}

TEST_F(BalanceTest, CheckNamesTwoOctantsThatReallyViolate) {
  std::mt19937_64 rng(8);
  for (int t = 0; t < 60; ++t) {
    GenOptions g;
    g.seed = rng();
    g.leaves = 50 + rng() % 200;
    g.max_level = 3 + static_cast<int>(rng() % 6);
    std::vector<Octant> leaves;
    ASSERT_OK(generate_octree(g, &leaves));
    if (reference::balance(leaves) == leaves) continue;
    const std::string db = import(leaves);
    BalanceOptions check;
    check.check_only = true;
    BalanceResult r;
    ASSERT_OK(balance_octree(db, check, &r));
    ASSERT_FALSE(r.balanced);
    expect_names_a_violation(r.violation, leaves);
  }
}

}  // namespace
}  // namespace weaver
