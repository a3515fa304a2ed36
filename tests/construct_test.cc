// Velocity models at known points, grid files good and bad, and construct's
// refinement rule checked leaf by leaf.
#include "construct/construct.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <random>

#include "construct/descent.h"
#include "construct/estimate.h"
#include "db/database.h"
#include "eighths_check.h"
#include "model/grid_model.h"
#include "model/velocity_model.h"
#include "schema/octant.h"
#include "test_mesh.h"
#include "test_util.h"

namespace weaver {
namespace {

Material at(const std::string& name, double x, double y, double z) {
  std::unique_ptr<VelocityModel> m;
  EXPECT_OK(make_model(name, "", &m));
  return m->at(x, y, z);
}

TEST(Models, ValuesAtKnownPoints) {
  const Material h = at("halfspace", 1, 2, 3);
  EXPECT_EQ(h.vp, 6000);
  EXPECT_EQ(h.vs, 3464);
  EXPECT_EQ(h.rho, 2700);
  EXPECT_EQ(at("loh1", 0, 0, 500).vs, 2000);
  EXPECT_EQ(at("loh1", 0, 0, 500).vp, 4000);
  EXPECT_EQ(at("loh1", 0, 0, 1500).vs, 3464);
  EXPECT_FLOAT_EQ(at("basin", 42000, 55000, 0).vs, 575);       // a bowl's centre, at the surface
  EXPECT_FLOAT_EQ(at("basin", 95000, 95000, 0).vs, 2600);      // rock outside the bowls
  EXPECT_FLOAT_EQ(at("basin", 95000, 95000, 30000).vs, 3900);  // deep rock, capped
  EXPECT_FLOAT_EQ(at("basin", 42000, 55000, 1000).vs, 1325);   // Vs rises with depth
  std::unique_ptr<VelocityModel> m;
  EXPECT_TRUE(make_model("marble", "", &m).is_invalid_argument());
  EXPECT_TRUE(make_model("grid", "", &m).is_invalid_argument());
}

// The basin's soft inclusions: about one per four 600 m cells of the rock
// above 5 km, 40 m in radius, none in the sediments or deeper.
TEST(Models, BasinInclusionsSitInShallowRockOnly) {
  std::unique_ptr<VelocityModel> m;
  ASSERT_OK(make_model("basin", "", &m));
  auto soft_points = [&](double x0, double y0, double z0) {
    int n = 0;
    for (double z = z0; z < z0 + 2400; z += 20)
      for (double y = y0; y < y0 + 2400; y += 20)
        for (double x = x0; x < x0 + 2400; x += 20) n += m->at(x, y, z).vs == 100;
    return n;
  };
  // 64 cells, 16 inclusions expected; a 40 m ball holds about 34 points of a 20 m lattice.
  const int shallow_rock = soft_points(90000, 90000, 600);
  EXPECT_GT(shallow_rock, 4 * 20);
  EXPECT_LT(shallow_rock, 40 * 40);
  EXPECT_EQ(soft_points(90000, 90000, 6000), 0);  // below 5 km
  EXPECT_EQ(soft_points(41000, 54000, 0), 0);     // a bowl's sediments
}

// The basin's shared-work lattices (of Vs, and of whole materials) agree
// point by point with plain samples, on the lattices construct asks for
// (2 to 8 points a side).
void expect_lattice_matches_sampling(const VelocityModel& m, double x, double y, double z, double h,
                                     int n, int* soft) {
  double axes[3][8] = {};
  for (int i = 0; i < n; ++i)
    axes[0][i] = x + i * h, axes[1][i] = y + i * h, axes[2][i] = z + i * h;
  float fast[512], plain[512];
  m.vs_on_lattice(axes[0], axes[1], axes[2], n, fast);
  m.VelocityModel::vs_on_lattice(axes[0], axes[1], axes[2], n, plain);
  Material materials[512];
  m.materials_on_lattice(axes[0], axes[1], axes[2], n, materials);
  for (int p = 0; p < n * n * n; ++p) {
    ASSERT_EQ(fast[p], plain[p]) << x << " " << y << " " << z << " " << h << " n " << n << " at "
                                 << p;
    const Material one = m.at(axes[0][p % n], axes[1][p / n % n], axes[2][p / (n * n)]);
    ASSERT_EQ(std::memcmp(&materials[p], &one, sizeof one), 0) << x << " " << y << " " << z;
    *soft += fast[p] == 100;
  }
  // Columns of their own depths, as a model under a ground asks: each
  // column shifted, some above z = 0.
  double zs[512];
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      for (int k = 0; k < n; ++k)
        zs[(j * n + i) * n + k] = axes[2][k] + ((i * 7 + j * 13) % 11 - 3) * h / 3;
  m.vs_on_columns(axes[0], axes[1], zs, n, fast);
  m.materials_on_columns(axes[0], axes[1], zs, n, materials);
  for (int p = 0; p < n * n * n; ++p) {
    const int i = p % n, j = p / n % n, k = p / (n * n);
    const Material one = m.at(axes[0][i], axes[1][j], zs[(j * n + i) * n + k]);
    ASSERT_EQ(fast[p], one.vs) << x << " " << y << " " << z << " " << h << " n " << n;
    ASSERT_EQ(std::memcmp(&materials[p], &one, sizeof one), 0) << x << " " << y << " " << z;
    *soft += fast[p] == 100;
  }
}

// Points of a 20 m lattice inside the basin's inclusions, in 64 cells of
// shallow rock.
std::vector<std::array<double, 3>> soft_points(const VelocityModel& m) {
  std::vector<std::array<double, 3>> soft;
  for (double pz = 0; pz < 2400; pz += 20)
    for (double py = 90000; py < 92400; py += 20)
      for (double px = 90000; px < 92400; px += 20)
        if (m.at(px, py, pz).vs == 100) soft.push_back({px, py, pz});
  return soft;
}

TEST(Models, BasinLatticeMatchesSampling) {
  // Sibling centres, an octant's samples, its children's, and the centres
  // of a block of leaves (4 and 8 a side).
  constexpr int kSizes[5] = {2, 3, 5, 4, 8};
  std::unique_ptr<VelocityModel> m;
  ASSERT_OK(make_model("basin", "", &m));
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> x(0, 100000), z(0, 8000), h(1, 400);
  int soft = 0;
  for (int i = 0; i < 20000; ++i) {
    expect_lattice_matches_sampling(*m, x(rng), x(rng), z(rng), h(rng), kSizes[i % 5], &soft);
  }
  // Small lattices at and around inclusions (the cached cell of the fast
  // path), across 600 m cell borders too.
  const std::vector<std::array<double, 3>> inclusions = soft_points(*m);
  ASSERT_GT(inclusions.size(), 20u);
  std::uniform_real_distribution<double> jitter(-60, 60), small(0.5, 40);
  soft = 0;
  for (int i = 0; i < 20000; ++i) {
    const auto& c = inclusions[rng() % inclusions.size()];
    expect_lattice_matches_sampling(*m, c[0] + jitter(rng), c[1] + jitter(rng), c[2] + jitter(rng),
                                    small(rng), kSizes[i % 5], &soft);
  }
  EXPECT_GT(soft, 20000);  // the lattices do meet inclusions
}

// Every point of a box, the corners and lattice points construct samples
// among them, has its Vs within the model's bounds over the box; the basin's
// boxes include ones across bowl rims, ones around, across and inside
// inclusions, and ones across 600 m cell borders.
void expect_bounds_hold(const VelocityModel& m, const double lo[3], double edge,
                        std::mt19937_64& rng, int* settled = nullptr, float* soft = nullptr) {
  const double hi[3] = {lo[0] + edge, lo[1] + edge, lo[2] + edge};
  float vs_lo, vs_hi;
  ASSERT_TRUE(m.vs_bounds(lo, hi, &vs_lo, &vs_hi));
  if (soft != nullptr) *soft = vs_hi;
  ASSERT_LE(vs_lo, vs_hi);
  std::uniform_real_distribution<double> t(0, 1);
  auto check = [&](double x, double y, double z) {
    const float vs = m.at(x, y, z).vs;
    ASSERT_TRUE(vs >= vs_lo && vs <= vs_hi)
        << "box (" << lo[0] << ", " << lo[1] << ", " << lo[2] << ") edge " << edge << ": Vs " << vs
        << " at (" << x << ", " << y << ", " << z << ") outside [" << vs_lo << ", " << vs_hi << "]";
  };
  for (int k = 0; k < 5; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 5; ++i)
        check(lo[0] + i * edge / 4, lo[1] + j * edge / 4, lo[2] + k * edge / 4);
  for (int p = 0; p < 200; ++p)
    check(lo[0] + t(rng) * edge, lo[1] + t(rng) * edge, lo[2] + t(rng) * edge);
  if (settled != nullptr) *settled += vs_lo == vs_hi;
}

// The boxes the bounds tests ask about, each to f(model, lo, edge, kind):
// kind 0, boxes of every size anywhere in the domain (reaching `past` m
// beyond its near sides), for each model; for the basin, kind 1, boxes of
// 1 to soft_edge m at points in and near inclusions, and kind 2, boxes
// across the rim and floor of the bowl at (22, 24) km.
template <class F>
void each_test_box(double past, double soft_edge, std::mt19937_64& rng, const F& f) {
  std::uniform_real_distribution<double> unit(0, 1);
  for (const char* name : {"halfspace", "loh1", "basin"}) {
    std::unique_ptr<VelocityModel> m;
    ASSERT_OK(make_model(name, "", &m));
    for (int i = 0; i < 3000; ++i) {
      const double edge = std::ldexp(100000.0, -int(rng() % 16));
      const double lo[3] = {unit(rng) * 100000 - past, unit(rng) * 100000 - past,
                            unit(rng) * 8000 - past};
      f(*m, lo, edge, 0);
    }
  }
  std::unique_ptr<VelocityModel> m;
  ASSERT_OK(make_model("basin", "", &m));
  const std::vector<std::array<double, 3>> soft = soft_points(*m);
  ASSERT_GT(soft.size(), 20u);
  std::uniform_real_distribution<double> jitter(-60, 60), edge(1, soft_edge);
  for (int i = 0; i < 20000; ++i) {
    const auto& c = soft[rng() % soft.size()];
    const double lo[3] = {c[0] + jitter(rng), c[1] + jitter(rng), c[2] + jitter(rng)};
    f(*m, lo, edge(rng), 1);
  }
  for (int i = 0; i < 5000; ++i) {
    const double a = unit(rng) * 6.2832, r = 11000 * (0.9 + 0.2 * unit(rng));
    const double lo[3] = {22000 + r * std::cos(a), 24000 + r * std::sin(a), unit(rng) * 2500};
    f(*m, lo, std::ldexp(800.0, -int(rng() % 8)), 2);
  }
}

TEST(Models, VsBoundsHoldAtEveryPointOfTheBox) {
  std::mt19937_64 rng(11);
  std::map<std::string, int> settled;
  int inside = 0;
  each_test_box(0, 100, rng,
                [&](const VelocityModel& m, const double lo[3], double edge, int kind) {
                  int one = 0;
                  float vs_hi = 0;
                  expect_bounds_hold(m, lo, edge, rng, &one, &vs_hi);
                  if (kind == 0) settled[m.describe()] += one;
                  // boxes wholly inside an inclusion are settled as such
                  if (kind == 1) inside += one && vs_hi == 100;
                });
  ASSERT_EQ(settled.size(), 3u);
  for (const auto& [model, n] : settled) EXPECT_GT(n, 0) << model;
  EXPECT_GT(inside, 100);
}

// The eight halves' bounds at once are eight calls' bounds, bit for bit,
// for every model (the basin shares its work between them; the others take
// the default), some halves wanted and some not.
void expect_eighths_of(const VelocityModel& m, const double lo[3], double edge,
                       std::mt19937_64& rng, int* looked) {
  double edges[3][3];
  for (int a = 0; a < 3; ++a) edges[a][0] = lo[a], edges[a][1] = lo[a] + edge / 2;
  for (int a = 0; a < 3; ++a) edges[a][2] = lo[a] + edge;
  bool want[8];
  for (bool& w : want) w = rng() % 4 != 0;
  int refused = 0;
  expect_eighths_as_calls(m, edges, want, looked, &refused);
  ASSERT_EQ(refused, 0);
}

TEST(Models, BoundsOfEighthsAreThoseOfEachEighth) {
  std::mt19937_64 rng(12);
  int looked = 0;
  each_test_box(50, 1300, rng, [&](const VelocityModel& m, const double lo[3], double edge, int) {
    expect_eighths_of(m, lo, edge, rng, &looked);
  });
  EXPECT_GT(looked, 150000);
}

TEST(GridModel, InterpolatesAndClamps) {
  testing::TempDir dir;
  GridSpec s;
  s.nx = 2, s.ny = 2, s.nz = 3;
  s.dz = 100;
  std::vector<Material> v;
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i)
        v.push_back({float(3000 + 100 * k + 10 * i), float(1000 + 100 * k), 2000});
  ASSERT_OK(write_grid_model(dir.file("g"), s, v));
  std::unique_ptr<VelocityModel> m;
  ASSERT_OK(make_model("grid", dir.file("g"), &m));
  EXPECT_FLOAT_EQ(m->at(0.5, 0.5, 50).vs, 1050);  // halfway between k=0 and k=1
  EXPECT_FLOAT_EQ(m->at(0.5, 0, 0).vp, 3005);     // halfway in x
  EXPECT_FLOAT_EQ(m->at(-9, -9, 1e6).vs, 1200);   // clamped to the last layer
}

TEST(GridModel, BadFilesGetOneLineErrorsNamingTheFile) {
  testing::TempDir dir;
  auto expect_bad = [&](const std::string& body, const std::string& words) {
    const std::string path = dir.file("bad");
    std::ofstream(path, std::ios::binary) << body;
    std::unique_ptr<VelocityModel> m;
    const Status st = make_model("grid", path, &m);
    ASSERT_FALSE(st.ok());
    EXPECT_NE(st.message().find(path), std::string::npos) << st.message();
    EXPECT_NE(st.message().find(words), std::string::npos) << st.message();
    EXPECT_EQ(st.message().find('\n'), std::string::npos);
  };
  expect_bad("hello\n", "not a weaver grid model");
  expect_bad("weaver-grid 1\n2 2\n0 0 0\n1 1 1\n", "line 2");
  expect_bad("weaver-grid 1\n1 2 2\n0 0 0\n1 1 1\n", "dimensions");
  expect_bad("weaver-grid 1\n2 2 2\n0 0 0\n1 0 1\n", "spacing");
  expect_bad("weaver-grid 1\n2 2 2\n0 0 0\n1 1 1\nshort", "expected 96 bytes");
  std::string body = "weaver-grid 1\n2 2 2\n0 0 0\n1 1 1\n";
  const float bad[3] = {3000, -1, 2000};
  for (int i = 0; i < 8; ++i) body.append(reinterpret_cast<const char*>(bad), 12);
  expect_bad(body, "non-positive");
  std::unique_ptr<VelocityModel> m;
  EXPECT_TRUE(make_model("grid", dir.file("missing"), &m).is_not_found());
}

// Vs_min over the 27 sample points, written out independently of construct.
double vs_min(const VelocityModel& m, const Octant& o, double tick, double floor) {
  double v = 1e300;
  const double e = octant_edge(o) * tick;
  for (double fz : {0.0, 0.5, 1.0})
    for (double fy : {0.0, 0.5, 1.0})
      for (double fx : {0.0, 0.5, 1.0}) {
        v = std::min<double>(
            v, m.at(o.x * tick + fx * e, o.y * tick + fy * e, o.z * tick + fz * e).vs);
      }
  return std::max(v, floor);
}

TEST(Construct, EveryLeafMeetsTheRuleAndNoneIsFinerThanNeeded) {
  struct Case {
    const char* model;
    double freq;
    std::array<double, 3> domain;
    double vs_min;
  };
  for (const Case& c : {Case{"loh1", 0.8, {20000, 20000, 10000}, 0},
                        Case{"basin", 0.15, {100000, 100000, 37500}, 0},
                        Case{"basin", 0.3, {100000, 50000, 37500}, 600}}) {
    testing::TempDir dir;
    ConstructOptions o;
    o.balanced = false;  // the descent's own leaves
    o.model = c.model;
    o.freq = c.freq;
    o.domain_m = c.domain;
    o.vs_min = c.vs_min;
    ConstructPlan plan;
    ConstructResult r;
    ASSERT_OK(construct_octree(dir.file("db"), o, &plan, &r));
    std::unique_ptr<VelocityModel> model;
    ASSERT_OK(make_model(c.model, "", &model));
    std::unique_ptr<Database> db;
    std::unique_ptr<BTree> t;
    ASSERT_OK(Database::open(dir.file("db"), Database::Mode::kRead, false, &db));
    ASSERT_OK(db->open_table(kOctantTable, 1 << 20, &t));
    BTreeCursor cur;
    ASSERT_OK(t->seek_cursor(0, &cur));
    double volume = 0, worst_ppw = HUGE_VAL, smallest = HUGE_VAL, largest = 0;
    uint64_t n = 0;
    while (cur.valid()) {
      const Octant leaf = octant_from_key(cur.key());
      const double edge = octant_edge(leaf) * plan.tick_m;
      volume += edge * edge * edge;
      const double leaf_vs = vs_min(*model, leaf, plan.tick_m, c.vs_min);
      worst_ppw = std::min(worst_ppw, leaf_vs / (c.freq * edge));
      smallest = std::min(smallest, edge), largest = std::max(largest, edge);
      const double limit = leaf_vs / (c.freq * o.ppw);
      ASSERT_TRUE(edge <= limit || leaf.level == o.max_level) << c.model << " leaf too big";
      if (leaf.level > plan.block_level) {
        const Octant p = octant_parent(leaf);
        const double pedge = octant_edge(p) * plan.tick_m;
        ASSERT_GT(pedge, vs_min(*model, p, plan.tick_m, c.vs_min) / (c.freq * o.ppw))
            << c.model << ": the parent of a leaf already meets the rule";
      }
      float mat[3];
      std::memcpy(mat, cur.payload(), sizeof mat);
      const double h = edge / 2;
      EXPECT_FLOAT_EQ(
          mat[1],
          model->at(leaf.x * plan.tick_m + h, leaf.y * plan.tick_m + h, leaf.z * plan.tick_m + h)
              .vs);
      ++n;
      ASSERT_OK(cur.next());
    }
    EXPECT_EQ(n, r.elements);
    EXPECT_NEAR(r.worst_ppw, worst_ppw, 1e-9 * worst_ppw) << c.model;
    EXPECT_EQ(r.smallest_edge_m, smallest) << c.model;
    EXPECT_EQ(r.largest_edge_m, largest) << c.model;
    const double domain = c.domain[0] * c.domain[1] * c.domain[2];
    EXPECT_NEAR(volume / domain, 1.0, 1e-9) << c.model << ": leaves must tile the domain";
  }
}

// Subtrees on 1 to 4 threads, with budgets from the smallest (subtrees past
// a small cap are visited again as their children) to the default: the
// same table byte for byte, and the same figures.
TEST(Construct, AnyThreadCountAndBudgetWritesTheSameTable) {
  // Under the sanitizers: the basin, on 1 and 3 threads.
  const std::vector<const char*> models = testing::small_scale()
                                              ? std::vector<const char*>{"basin"}
                                              : std::vector<const char*>{"basin", "loh1"};
  const std::vector<int> thread_counts =
      testing::small_scale() ? std::vector<int>{1, 3} : std::vector<int>{1, 2, 3, 4};
  for (const char* model : models) {
    std::string first;
    ConstructResult first_r;
    uint64_t over = 0;
    for (int threads : thread_counts) {
      for (uint64_t budget : {MemoryBudget::kMinBytes, MemoryBudget::kDefaultBytes}) {
        testing::TempDir dir;
        ConstructOptions o;
        o.model = model;
        o.freq = 0.25;
        o.threads = threads;
        o.memory = MemoryBudget(budget);
        ConstructPlan plan;
        ConstructResult r;
        ASSERT_OK(construct_octree(dir.file("db"), o, &plan, &r));
        const std::string bytes = testing::table_bytes(dir.file("db"));
        if (first.empty()) {
          first = bytes;
          first_r = r;
        }
        SCOPED_TRACE(std::string(model) + ", " + std::to_string(threads) + " threads, budget " +
                     std::to_string(budget));
        ASSERT_EQ(bytes, first);
        EXPECT_EQ(r.elements, first_r.elements);
        EXPECT_EQ(r.levels, first_r.levels);
        EXPECT_EQ(r.smallest_edge_m, first_r.smallest_edge_m);
        EXPECT_EQ(r.worst_ppw, first_r.worst_ppw);
        EXPECT_GT(r.subtrees, 8u);
        over += r.subtrees_over;
      }
    }
    EXPECT_GT(over, 0u) << model << ": no subtree went past its cap";
  }
}

// Octants settled by the model's bounds are the ones samples would have
// settled the same way, and so are the blocks of leaves the bounds show to
// be of one level: the tables, balanced and not, and the figures are
// those of a construct that samples every octant, on a corner of the basin
// holding part of a bowl and a few hundred inclusions (3 m leaves in 3 km
// of rock: the basin's deepest grading; its blocks lie in inclusions), on a
// corner at 0.5 Hz (blocks in graded rock and sediment, a bowl), and on
// LOH.1 (blocks in its layers).
TEST(Construct, ModelBoundsChangeNothingButTheSamplesTaken) {
  struct Case {
    const char* model;
    double freq;
    std::array<double, 3> domain_m;
  };
  const Case cases[] = {{"basin", 1.0, {14000, 14000, 3000}},
                        {"basin", 0.5, {25000, 25000, 6250}},
                        {"loh1", 2.0, {8000, 4000, 3000}}};
  for (const Case& c : cases) {
    for (bool balanced : {true, false}) {
      std::string tables[2];
      ConstructResult results[2];
      for (int bounds = 0; bounds < 2; ++bounds) {
        testing::TempDir dir;
        ConstructOptions o;
        o.model = c.model;
        o.freq = c.freq;
        o.domain_m = c.domain_m;
        o.balanced = balanced;
        o.model_bounds = bounds == 1;
        o.threads = 2;
        ConstructPlan plan;
        ASSERT_OK(construct_octree(dir.file("db"), o, &plan, &results[bounds]));
        tables[bounds] = testing::table_bytes(dir.file("db"));
      }
      SCOPED_TRACE(std::string(c.model) + (balanced ? ", balanced" : ", unbalanced"));
      EXPECT_GT(results[0].elements, 10000u);
      // Without bounds every leaf is judged; with them most are written as
      // blocks of one level, which must change nothing either.
      EXPECT_EQ(results[0].blocked, 0u);
      EXPECT_GT(results[1].blocked, 2000u);
      ASSERT_EQ(tables[1], tables[0]);
      EXPECT_EQ(results[1].levels, results[0].levels);
      EXPECT_EQ(results[1].worst_ppw, results[0].worst_ppw);
      EXPECT_EQ(results[1].smallest_edge_m, results[0].smallest_edge_m);
      EXPECT_EQ(results[1].largest_edge_m, results[0].largest_edge_m);
    }
  }
}

// The subtrees come block by block in Z-order, each split where the descent
// splits it down to the task level, but for octants the caller takes whole:
// the same list as every block of the domain, sorted by key and split so
// (the reference), for block counts that are no power of two; and a domain of 999 x 999 x 374
// blocks of 100 m (373M of them, 6 GB as a list) gives its first subtrees at once, in little memory
// (the list was once built whole before the first).
TEST(Construct, SubtreesComeInZOrderWithoutListingEveryBlock) {
  std::unique_ptr<VelocityModel> model;
  ASSERT_OK(make_model("basin", "", &model));
  size_t taken_whole_in_all = 0;
  for (const std::array<double, 3> domain :
       {std::array<double, 3>{100000, 80000, 37500}, {70000, 50000, 30000}, {5000, 3000, 1000}}) {
    ConstructOptions o;
    o.domain_m = domain;
    o.freq = 0.2;
    ConstructPlan p;
    ASSERT_OK(plan_construct(o, &p));
    const Descent descent(o, p, *model);
    const int task_level = p.block_level + 2;
    // Without octants taken whole, and with a third of them (by key).
    const auto a_third = [](const Octant& x) {
      return octant_key(x) * 0x9E3779B97F4A7C15ULL % 3 == 0;
    };
    for (const SubtreeList::Whole& whole : {SubtreeList::Whole{}, SubtreeList::Whole{a_third}}) {
      std::vector<Octant> want, stack;
      const uint32_t e = octant_edge(p.block_level);
      for (uint32_t k = 0; k < p.blocks[2]; ++k)
        for (uint32_t j = 0; j < p.blocks[1]; ++j)
          for (uint32_t i = 0; i < p.blocks[0]; ++i)
            stack.push_back({i * e, j * e, k * e, uint8_t(p.block_level)});
      std::sort(stack.begin(), stack.end(),
                [](const Octant& a, const Octant& b) { return octant_key(a) > octant_key(b); });
      size_t taken_whole = 0;  // octants the list would split, taken whole
      while (!stack.empty()) {
        const Octant top = stack.back();
        stack.pop_back();
        const bool whole_here = top.level < task_level && whole && whole(top);
        if (top.level >= task_level || whole_here || !descent.splits(top)) {
          want.push_back(top);
          taken_whole += whole_here && descent.splits(top);
          continue;
        }
        for (int c = 7; c >= 0; --c) stack.push_back(octant_child(top, c));
      }
      if (!whole) {
        EXPECT_EQ(taken_whole, 0u);
      }
      taken_whole_in_all += taken_whole;
      SubtreeList list(descent, p, task_level, whole);
      std::vector<Octant> got;
      for (Octant r; list.next(&r);) got.push_back(r);
      ASSERT_EQ(got.size(), want.size()) << domain[0] << " x " << domain[1];
      for (size_t i = 0; i < got.size(); ++i) {
        ASSERT_EQ(octant_key(got[i]), octant_key(want[i])) << i;
      }
    }
  }
  EXPECT_GT(taken_whole_in_all, 0u);
  ConstructOptions o;
  o.domain_m = {99900, 99900, 37400};
  o.freq = 0.25;
  ConstructPlan p;
  ASSERT_OK(plan_construct(o, &p));
  ASSERT_EQ(p.blocks, (std::array<uint32_t, 3>{999, 999, 374}));
  const Descent descent(o, p, *model);
  SubtreeList list(descent, p, p.block_level);
  Octant previous{};
  for (int i = 0; i < 1000; ++i) {
    Octant r;
    ASSERT_TRUE(list.next(&r));
    if (i > 0) {
      EXPECT_LT(octant_key(previous), octant_key(r));
    }
    previous = r;
  }
  // The 373M blocks as a list were 6 GB; this test's process stays far below.
  rusage usage{};
  ASSERT_EQ(getrusage(RUSAGE_SELF, &usage), 0);
  EXPECT_LT(usage.ru_maxrss, 2L << 20) << "KB at peak";
}

TEST(Construct, ResolvesDomainsIntoBlocksAndRejectsBadOptions) {
  ConstructOptions o;
  ConstructPlan p;
  ASSERT_OK(plan_construct(o, &p));
  EXPECT_EQ(p.block_level, 3);
  EXPECT_EQ(p.blocks, (std::array<uint32_t, 3>{8, 8, 3}));
  EXPECT_FALSE(p.rounded_up);
  // Not a power of two of blocks along the longest side: 40 x 32 x 15 blocks
  // of 2.5 km in a root of 64 (160 km), the domain exactly.
  o.domain_m = {100000, 80000, 37500};
  ASSERT_OK(plan_construct(o, &p));
  EXPECT_FALSE(p.rounded_up);
  EXPECT_EQ(p.block_level, 6);
  EXPECT_EQ(p.blocks, (std::array<uint32_t, 3>{40, 32, 15}));
  EXPECT_DOUBLE_EQ(p.root_edge_m, 160000);
  EXPECT_EQ(p.domain_m, o.domain_m);
  // No whole number of blocks up to 1024 along the longest side: rounded up
  // to blocks of 1/128 of it, each side by less than one block.
  o.domain_m = {1000, 333.3, 10};
  ASSERT_OK(plan_construct(o, &p));
  EXPECT_TRUE(p.rounded_up);
  EXPECT_EQ(p.block_level, 7);
  EXPECT_DOUBLE_EQ(p.root_edge_m, 1000);
  for (int a = 0; a < 3; ++a) {
    EXPECT_GE(p.domain_m[a], o.domain_m[a]);
    EXPECT_LT(p.domain_m[a], o.domain_m[a] + 1000.0 / 128);
  }
  o = ConstructOptions{};
  o.freq = 0;
  EXPECT_TRUE(plan_construct(o, &p).is_invalid_argument());
  o = ConstructOptions{};
  o.min_level = 9;
  o.max_level = 4;
  EXPECT_TRUE(plan_construct(o, &p).is_invalid_argument());
  o = ConstructOptions{};
  o.model = "lava";
  EXPECT_TRUE(plan_construct(o, &p).is_invalid_argument());
}

// The disk check refuses a run that cannot fit even where the materials pack
// best, names that figure and the free space, and lets one through that
// fits at the best packing though not at the worst (the plan says so); the
// element cap holds before it.  The file system's own free space is the
// measure: the sizes are set far past any disk and far under it.
TEST(Construct, TheDiskCheckRefusesOnlyWhatCannotFitAtTheBestPacking) {
  testing::TempDir dir;
  const double free = free_disk_bytes(dir.file("db"));
  ASSERT_GT(free, 1e6) << "the test needs a file system it can measure";
  ConstructOptions o;
  ConstructEstimate e;
  e.elements = 1000;
  e.least_disk_bytes = free * 1e3, e.disk_bytes = free * 1e4;
  Status st = check_construct_fits(o, e, dir.file("db"));
  ASSERT_TRUE(st.is_invalid_argument()) << st.to_string();
  EXPECT_NE(st.message().find("needing at least"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("free"), std::string::npos) << st.message();
  e.least_disk_bytes = 1e3;  // the worst still far past the disk
  EXPECT_TRUE(check_construct_fits(o, e, dir.file("db")).ok());
  o.max_elements = 999;
  EXPECT_TRUE(check_construct_fits(o, e, dir.file("db")).is_invalid_argument());
}

// The least disk grows with the elements and lies under the worst, for
// `construct` and for `mesh` (which adds the node table), packed or not.
TEST(Construct, TheDiskEstimateBracketsTheTables) {
  double last_least = 0;
  for (double freq : {0.25, 0.5}) {
    for (bool mesh : {false, true}) {
      ConstructOptions o;
      o.model = "basin";
      o.freq = freq;
      o.whole_pipeline = mesh;
      ConstructPlan p;
      ASSERT_OK(plan_construct(o, &p));
      const ConstructEstimate e = planned_estimate(p);
      EXPECT_GT(e.elements, 1e5);
      EXPECT_GT(e.least_disk_bytes, 0.9 * e.elements) << freq << " " << mesh;
      EXPECT_LT(e.least_disk_bytes, e.disk_bytes / 3) << freq << " " << mesh;
      if (mesh) {
        EXPECT_GT(e.least_disk_bytes, last_least) << "mesh adds the node table";
      }
      last_least = e.least_disk_bytes;
    }
  }
}
}  // namespace
}  // namespace weaver
