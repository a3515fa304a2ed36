// The model database: imports from the etree library's own files and from
// grid files, answered by the aggregate-hit query, and construct from it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "construct/construct.h"
#include "db/database.h"
#include "eighths_check.h"
#include "model/grid_model.h"
#include "model/material_merge.h"
#include "modeldb/db_model.h"
#include "modeldb/grid_import.h"
#include "modeldb/model_import.h"
#include "storage/btree.h"
#include "test_mesh.h"
#include "test_util.h"

namespace weaver {
namespace {

std::string fresh(const std::string& name) { return testing::fresh_path("model_db_" + name); }

std::string fixture(const std::string& name) {
  return std::string(WEAVER_SOURCE_DIR) + "/tests/data/etree/" + name;
}

class FromEtree : public ::testing::TestWithParam<const char*> {};

// Every pixel the etree library searched gives, through the model database,
// the values the library answered (merging at tolerance 0 keeps them).
TEST_P(FromEtree, AnswersAsTheLibrarysSearchDid) {
  const std::string name = GetParam();
  const std::string db = fresh(name);
  ModelImportOptions o;
  o.from = "etree:" + fixture(name + ".e");
  ModelImportResult r;
  const Status st = import_model(db, o, &r);
  ASSERT_TRUE(st.ok()) << st.to_string();
  EXPECT_LT(r.octants, r.read);  // the fixtures' uniform sibling sets merged
  std::unique_ptr<DbModel> m;
  ASSERT_TRUE(DbModel::open(db, MemoryBudget(), 1, &m).ok());
  EXPECT_DOUBLE_EQ(m->info().tick_m * kRootEdge, 100000.0);
  std::ifstream in(fixture(name + ".search"));
  std::string line;
  int checked = 0;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    uint32_t p[3];
    s >> p[0] >> p[1] >> p[2];
    std::string skip;
    for (int i = 0; i < 5; ++i) s >> skip;  // "->" and the hit's address
    double want[5] = {0, 0, 0, 0, 0};
    for (int i = 0; i < 5 && s >> want[i]; ++i) {
    }
    double at[3];
    for (int a = 0; a < 3; ++a) at[a] = ((p[a] >> 11) + 0.5) * m->info().tick_m;
    ModelHit h;
    ASSERT_TRUE(m->lookup(at[0], at[1], at[2], &h).ok()) << line;
    for (int f = 0; f < (m->info().has_q ? 5 : 3); ++f) {
      ASSERT_FLOAT_EQ(h.values[f], float(want[f])) << line << " field " << f;
    }
    ++checked;
  }
  EXPECT_EQ(checked, 2000);
  EXPECT_EQ(m->info().has_q, name == std::string("usgs"));
}

INSTANTIATE_TEST_SUITE_P(LibraryFiles, FromEtree, ::testing::Values("cmu", "usgs"));

TEST(ModelDb, RefusesAnEtreeWithoutTheFieldsAndLeavesNoTable) {
  const std::string db = fresh("nofields");
  ModelImportOptions o;
  o.from = "etree:" + fixture("make_fixtures.c");
  ModelImportResult r;
  EXPECT_FALSE(import_model(db, o, &r).ok());
  o.from = "grid:/nonexistent/file";
  const Status st = import_model(db, o, &r);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("/nonexistent/file"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(db + "/MANIFEST"));
}

TEST(ModelDb, RefusesAGridPointWithANonPositiveVelocityNamingIt) {
  GridSpec g;
  g.nx = g.ny = g.nz = 4;
  std::vector<Material> values(64, Material{2000, 1000, 2000});
  values[37].vs = -1;
  const std::string grid = ::testing::TempDir() + "model_db_bad.grid";
  ASSERT_TRUE(write_grid_model(grid, g, values).ok());
  const std::string db = fresh("bad_grid");
  ModelImportOptions o;
  o.from = "grid:" + grid;
  ModelImportResult r;
  const Status st = import_model(db, o, &r);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find("grid point 37 has Vs -1"), std::string::npos) << st.message();
  std::unique_ptr<Database> d;
  ASSERT_TRUE(Database::open(db, Database::Mode::kRead, false, &d).ok());
  EXPECT_FALSE(d->has_table(kModelTable));  // nothing committed
}

// A grid of equal spacings: one octant per point, holding its values
// exactly; unequal spacings: trilinear values at the octants' centres.
TEST(ModelDb, GridPointsAreOctantCentres) {
  for (bool equal : {true, false}) {
    GridSpec g;
    g.nx = 37, g.ny = 21, g.nz = 11;
    g.x0 = 1000, g.y0 = -500, g.z0 = 0;
    g.dx = 100, g.dy = 100, g.dz = equal ? 100 : 250;
    std::vector<Material> values;
    for (int k = 0; k < g.nz; ++k)
      for (int j = 0; j < g.ny; ++j)
        for (int i = 0; i < g.nx; ++i) {
          const float vs = 300 + 7 * i + 13 * j + 29 * k + ((i * j + k) % 5 == 0 ? 50 : 0);
          values.push_back({2 * vs, vs, 1800 + vs / 10});
        }
    const std::string grid = ::testing::TempDir() + "model_db.grid";
    ASSERT_TRUE(write_grid_model(grid, g, values).ok());
    const std::string db = fresh(equal ? "grid_equal" : "grid_unequal");
    ModelImportOptions o;
    o.from = "grid:" + grid;
    o.memory = MemoryBudget(4ull << 20);
    ModelImportResult r;
    ASSERT_TRUE(import_model(db, o, &r).ok());
    std::unique_ptr<DbModel> m;
    ASSERT_TRUE(DbModel::open(db, MemoryBudget(), 1, &m).ok());
    std::unique_ptr<VelocityModel> ref;
    ASSERT_TRUE(load_grid_model(grid, &ref).ok());
    const int nz = equal ? g.nz : (g.nz - 1) * 250 / 100 + 1;
    EXPECT_EQ(r.read, uint64_t(g.nx) * g.ny * nz);
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < g.ny; ++j)
        for (int i = 0; i < g.nx; ++i) {
          const double x = g.x0 + 100 * i, y = g.y0 + 100 * j, z = g.z0 + 100 * k;
          ModelHit h;
          ASSERT_TRUE(m->lookup(x + 30, y - 40, z + 10, &h).ok());
          const Material want = ref->at(x, y, z);
          ASSERT_NEAR(h.values[1], want.vs, 1e-3 * want.vs) << i << " " << j << " " << k;
          ASSERT_NEAR(h.values[0], want.vp, 1e-3 * want.vp);
          if (equal) {
            ASSERT_EQ(h.values[1], values[(size_t(k) * g.ny + j) * g.nx + i].vs);
          }
        }
    // Outside the box: the nearest cell's value.
    ModelHit h, corner;
    ASSERT_TRUE(m->lookup(-1e6, -1e6, -1e6, &h).ok());
    ASSERT_TRUE(m->lookup(g.x0, g.y0, g.z0, &corner).ok());
    EXPECT_TRUE(h.clamped);
    EXPECT_EQ(h.values, corner.values);
  }
}

// A grid is read in blocks and merged a block at a time before the merger
// sees it (model/block_merge.h): the table is the one the merger writes
// when handed every grid point one by one, in key order (the slow
// reference), for block sizes that cut the grid unevenly, and tolerances.
TEST(ModelDb, BlockMergedGridImportIsTheOneByOneMerge) {
  GridSpec g;
  g.nx = 77, g.ny = 45, g.nz = 39;
  g.dx = g.dy = g.dz = 100;
  std::vector<Material> values;
  for (int k = 0; k < g.nz; ++k)
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        // Uniform layers, with a patch of noise and a smooth gradient.
        float vs = 500 + 400 * float(k / 8);
        if (i > 40 && j < 20 && k > 10) vs += float((i * 7 + j * 13 + k * 3) % 11);
        if (i < 16) vs += 0.5f * float(i);
        values.push_back({2 * vs, vs, 2000});
      }
  const std::string grid = ::testing::TempDir() + "model_db_blocks.grid";
  ASSERT_TRUE(write_grid_model(grid, g, values).ok());
  GridPlan plan;
  ModelInfo info;
  ASSERT_TRUE(plan_grid(grid, &plan, &info).ok());
  for (double tolerance : {0.0, 0.01, 0.3}) {
    // The reference: every point to the merger, in key order.
    std::vector<std::pair<uint64_t, ModelValues>> points, want;
    const uint32_t e = octant_edge(plan.level);
    for (int k = 0; k < g.nz; ++k)
      for (int j = 0; j < g.ny; ++j)
        for (int i = 0; i < g.nx; ++i) {
          const Material& m = values[(size_t(k) * g.ny + j) * g.nx + i];
          const Octant o{i * e, j * e, k * e, uint8_t(plan.level)};
          points.push_back({octant_key(o), ModelValues{m.vp, m.vs, m.rho, 0, 0}});
        }
    std::sort(points.begin(), points.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    MaterialMerger ref(tolerance, 3, [&](uint64_t key, const ModelValues& v) {
      want.push_back({key, v});
      return Status::Ok();
    });
    for (const auto& [key, v] : points) ASSERT_TRUE(ref.add(octant_from_key(key), v).ok());
    ASSERT_TRUE(ref.finish().ok());
    ASSERT_LT(want.size(), points.size() / 2) << "the grid should merge";
    for (uint64_t memory : {2ull << 20, 64ull << 20}) {  // blocks of 2^5 and 2^6 points a side
      const std::string db = fresh("blocks");
      ModelImportOptions o;
      o.from = "grid:" + grid;
      o.tolerance = tolerance;
      o.memory = MemoryBudget(memory);
      ModelImportResult r;
      ASSERT_TRUE(import_model(db, o, &r).ok());
      std::unique_ptr<Database> d;
      ASSERT_TRUE(Database::open(db, Database::Mode::kRead, false, &d).ok());
      std::unique_ptr<BTree> t;
      ASSERT_TRUE(d->open_table(kModelTable, 4 << 20, &t).ok());
      ASSERT_EQ(t->size(), want.size()) << tolerance << " " << memory;
      std::unique_ptr<Cursor> c;
      ASSERT_TRUE(t->seek(0, &c).ok());
      for (size_t n = 0; n < want.size(); ++n, (void)c->next()) {
        ASSERT_TRUE(c->valid());
        ASSERT_EQ(c->key(), want[n].first) << n;
        ASSERT_EQ(std::memcmp(c->payload(), want[n].second.data(), 12), 0) << n;
      }
    }
  }
}

// construct --model db:: every leaf carries the model's value at its centre,
// and obeys the rule with Vs taken from the model database.
TEST(ModelDb, ConstructSamplesTheModelDatabaseOnOneAndTwoThreads) {
  GridSpec g;
  g.nx = g.ny = 33, g.nz = 17;
  g.dx = g.dy = g.dz = 250;
  std::vector<Material> values;
  for (int k = 0; k < g.nz; ++k)
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        const float vs =
            (i - 16) * (i - 16) + (j - 10) * (j - 10) < 40 && k < 5 ? 300 : 1500 + 40 * k;
        values.push_back({2 * vs, vs, 2000});
      }
  const std::string grid = ::testing::TempDir() + "model_db_construct.grid";
  ASSERT_TRUE(write_grid_model(grid, g, values).ok());
  const std::string model = fresh("construct_model");
  ModelImportOptions io;
  io.from = "grid:" + grid;
  ModelImportResult ir;
  ASSERT_TRUE(import_model(model, io, &ir).ok());
  std::unique_ptr<DbModel> m;
  ASSERT_TRUE(DbModel::open(model, MemoryBudget(), 1, &m).ok());
  for (int threads : {1, 2}) {
    ConstructOptions o;
    o.model = "db:" + model;
    o.freq = 0.5;
    o.domain_m = {8000, 8000, 4000};
    o.threads = threads;
    ConstructPlan p;
    ConstructResult r;
    const std::string db = fresh("construct_" + std::to_string(threads));
    const Status st = construct_octree(db, o, &p, &r);
    ASSERT_TRUE(st.ok()) << st.to_string();
    ASSERT_GT(r.elements, 100u);
    std::unique_ptr<Database> d;
    ASSERT_TRUE(Database::open(db, Database::Mode::kRead, false, &d).ok());
    std::unique_ptr<BTree> t;
    ASSERT_TRUE(d->open_table("octants", 8 << 20, &t).ok());
    std::unique_ptr<Cursor> c;
    ASSERT_TRUE(t->seek(0, &c).ok());
    int fine = 0;
    // Every leaf; under the sanitizers every 16th (the threads' races are in
    // the construct, not in this check, which took 47 of TSan's 63 s).
    const uint64_t stride = testing::scaled(1, 16);
    for (uint64_t i = 0; c->valid(); (void)c->next(), ++i) {
      const Octant o8 = octant_from_key(c->key());
      if (i % stride != 0) continue;
      const double e = octant_edge(o8) * p.tick_m;
      float leaf[3];
      std::memcpy(leaf, c->payload(), 12);
      ModelHit h;
      ASSERT_TRUE(m->lookup((o8.x + octant_edge(o8) / 2.0) * p.tick_m,
                            (o8.y + octant_edge(o8) / 2.0) * p.tick_m,
                            (o8.z + octant_edge(o8) / 2.0) * p.tick_m, &h)
                      .ok());
      ASSERT_EQ(leaf[1], h.values[1]);
      // The 27 samples' least Vs from the model database bounds the edge.
      double vs_min = 1e30;
      for (int s = 0; s < 27; ++s) {
        ModelHit q;
        ASSERT_TRUE(m->lookup(o8.x * p.tick_m + e * (s % 3) / 2,
                              o8.y * p.tick_m + e * (s / 3 % 3) / 2,
                              o8.z * p.tick_m + e * (s / 9) / 2, &q)
                        .ok());
        vs_min = std::min<double>(vs_min, q.values[1]);
      }
      ASSERT_LE(e, vs_min / (o.freq * o.ppw) * (1 + 1e-9));
      fine += vs_min < 1000;
    }
    EXPECT_GT(fine, 0);  // the slow inclusion was found and refined
  }
}

// A grid of 80 x 80 x 56 points at 100 m (more than a region's raster holds,
// so its cells are shared by smaller octants), merged at 2%: slow inclusions in a
// gradient, uniform patches, and noise that keeps some points alone.
std::string import_bounds_model(const std::string& name) {
  GridSpec g;
  g.nx = g.ny = 80, g.nz = 56;
  g.dx = g.dy = g.dz = 100;
  std::vector<Material> values;
  uint64_t noise = 12345;
  for (int k = 0; k < g.nz; ++k)
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        noise = noise * 6364136223846793005ull + 1442695040888963407ull;
        float vs = k < 20 && (i / 9 + j / 7) % 3 == 0 ? 400 : 1000 + 30 * k;
        if ((i * 7 + j * 3 + k) % 97 == 0) vs += float(noise >> 54);  // lone points
        values.push_back({2 * vs, vs, 2000});
      }
  const std::string grid = ::testing::TempDir() + name + ".grid";
  EXPECT_TRUE(write_grid_model(grid, g, values).ok());
  const std::string model = fresh(name);
  ModelImportOptions io;
  io.from = "grid:" + grid;
  io.tolerance = 0.02;
  ModelImportResult ir;
  EXPECT_TRUE(import_model(model, io, &ir).ok());
  return model;
}

// The box the bounds tests focus their model on, inside the model's own.
constexpr double kBoundsFocusLo[3] = {300, 0, 100}, kBoundsFocusHi[3] = {7900, 7000, 5500};

// The model database at `model`, opened and focused on that box.
void open_focused(const std::string& model, std::unique_ptr<DbModel>* m) {
  ASSERT_TRUE(DbModel::open(model, MemoryBudget(), 1, m).ok());
  (*m)->focus(kBoundsFocusLo, kBoundsFocusHi);
}

// The bounds of a box hold the Vs at() gives at every point of it, corners
// and faces included (the reference: a 7 x 7 x 7 lattice over the closed
// box and 200 random points in it, each looked up alone), for boxes of every
// size, aligned or not, inside the focused region; and they are tight where
// the model is uniform.  Outside the region there are none.
TEST(ModelDb, VsBoundsHoldEveryPointOfTheBox) {
  std::unique_ptr<DbModel> m;
  ASSERT_NO_FATAL_FAILURE(open_focused(import_bounds_model("bounds"), &m));
  std::mt19937_64 rng(7);
  const auto uniform = [&](double a, double b) {
    return std::uniform_real_distribution<double>(a, b)(rng);
  };
  int tight = 0, boxes = 0;
  for (int n = 0; n < 400; ++n) {
    double lo[3], hi[3];
    const double side = n < 4 ? 6000 : std::pow(2.0, uniform(3, 12));
    for (int a = 0; a < 3; ++a) {
      const double room = kBoundsFocusHi[a] - kBoundsFocusLo[a];
      const double s = std::min(side, room);
      lo[a] = n % 2 ? kBoundsFocusLo[a] + std::floor(uniform(0, room - s) / 100) * 100
                    : uniform(kBoundsFocusLo[a], kBoundsFocusHi[a] - s);
      hi[a] = lo[a] + s;
    }
    float vs_lo = 0, vs_hi = 0;
    ASSERT_TRUE(m->vs_bounds(lo, hi, &vs_lo, &vs_hi));
    ++boxes;
    tight += vs_lo == vs_hi;
    const auto check = [&](double x, double y, double z) {
      const float vs = m->at(x, y, z).vs;
      ASSERT_LE(vs_lo, vs) << x << " " << y << " " << z << " in box " << n;
      ASSERT_GE(vs_hi, vs) << x << " " << y << " " << z << " in box " << n;
    };
    for (int k = 0; k < 7; ++k)
      for (int j = 0; j < 7; ++j)
        for (int i = 0; i < 7; ++i) {
          check(lo[0] + (hi[0] - lo[0]) * i / 6, lo[1] + (hi[1] - lo[1]) * j / 6,
                lo[2] + (hi[2] - lo[2]) * k / 6);
        }
    for (int r = 0; r < 200; ++r) {
      check(uniform(lo[0], hi[0]), uniform(lo[1], hi[1]), uniform(lo[2], hi[2]));
    }
  }
  EXPECT_GT(tight, boxes / 20) << "uniform patches should give equal bounds";
  const double out_lo[3] = {0, 0, 0}, out_hi[3] = {7900, 7900, 5500};
  float a = 0, b = 0;
  EXPECT_FALSE(m->vs_bounds(out_lo, out_hi, &a, &b)) << "the box reaches past the region";
}

// A reader's regions load one after another over any boxes, overlapping,
// nested, before and after each other in key order (a construct thread's
// subtrees and balances): each answers every point as the table does (the
// reference: a model never focused), and at its own model octant.
TEST(ModelDb, RegionsLoadedInAnyOrderAnswerAsTheTable) {
  const std::string model = import_bounds_model("regions");
  std::unique_ptr<DbModel> m, ref;
  ASSERT_TRUE(DbModel::open(model, MemoryBudget(), 1, &m).ok());
  ASSERT_TRUE(DbModel::open(model, MemoryBudget(), 1, &ref).ok());
  std::mt19937_64 rng(11);
  const auto uniform = [&](double a, double b) {
    return std::uniform_real_distribution<double>(a, b)(rng);
  };
  const double extent[3] = {8000, 8000, 5600};
  for (int n = 0; n < 300; ++n) {
    double lo[3], hi[3];
    const double side = std::pow(2.0, uniform(7, 13));
    for (int a = 0; a < 3; ++a) {
      lo[a] = uniform(0, std::max(1.0, extent[a] - side));
      hi[a] = std::min(extent[a], lo[a] + side);
    }
    m->focus(lo, hi);
    for (int r = 0; r < 100; ++r) {
      const double p[3] = {uniform(lo[0], hi[0]), uniform(lo[1], hi[1]), uniform(lo[2], hi[2])};
      ModelHit got, want;
      ASSERT_TRUE(m->lookup(p[0], p[1], p[2], &got).ok()) << "box " << n;
      ASSERT_TRUE(ref->lookup(p[0], p[1], p[2], &want).ok());
      ASSERT_EQ(got.octant, want.octant)
          << "box " << n << " at " << p[0] << " " << p[1] << " " << p[2];
      ASSERT_EQ(got.values, want.values) << "box " << n;
    }
  }
}

// Points outside any region (each answered by the table, or by an octant
// the reader found there before) get the table's own octant: one that holds
// the point and is a record of the table with those values, checked against
// the table directly.  Points come in clusters, several to a model cell,
// and clusters again where earlier ones were, as the lattices around a
// subtree ask them.
TEST(ModelDb, PointsOutsideTheRegionAnswerAsTheTable) {
  const std::string model = import_bounds_model("outside_region");
  std::unique_ptr<DbModel> m;
  ASSERT_TRUE(DbModel::open(model, MemoryBudget(), 1, &m).ok());
  std::unique_ptr<Database> db;
  ASSERT_TRUE(Database::open(model, Database::Mode::kRead, false, &db).ok());
  std::unique_ptr<BTree> table;
  ASSERT_TRUE(db->open_table(kModelTable, 1 << 20, &table).ok());
  const ModelInfo& info = m->info();
  std::mt19937_64 rng(5);
  const auto uniform = [&](double a, double b) {
    return std::uniform_real_distribution<double>(a, b)(rng);
  };
  std::vector<std::array<double, 3>> centres;
  for (int n = 0; n < 20000; ++n) {
    if (centres.empty() || rng() % 4 != 0) {
      centres.push_back({uniform(0, 7999), uniform(0, 7999), uniform(0, 5599)});
    }
    const std::array<double, 3>& c = centres[rng() % centres.size()];
    double p[3];
    for (int a = 0; a < 3; ++a) {  // within the model's box: no clamping
      p[a] = std::clamp(c[a] + uniform(-150, 150), info.origin_m[a],
                        info.origin_m[a] + info.extent_m[a] - 1);
    }
    ModelHit h;
    ASSERT_TRUE(m->lookup(p[0], p[1], p[2], &h).ok()) << n;
    ASSERT_FALSE(h.clamped) << n;
    const uint32_t corner[3] = {h.octant.x, h.octant.y, h.octant.z};
    for (int a = 0; a < 3; ++a) {
      const double lo = info.origin_m[a] + corner[a] * info.tick_m;
      ASSERT_GE(p[a], lo) << n << " axis " << a;
      ASSERT_LT(p[a], lo + octant_edge(h.octant) * info.tick_m) << n << " axis " << a;
    }
    std::byte record[sizeof(ModelValues)] = {};
    bool found = false;
    ASSERT_TRUE(table->get(octant_key(h.octant), record, &found).ok());
    ASSERT_TRUE(found) << n << ": no such octant in the table";
    ASSERT_EQ(std::memcmp(record, h.values.data(), table->options().schema.record_size()), 0) << n;
  }
}

// A lattice of samples (construct's 3 x 3 x 3 and 5 x 5 x 5, the 2 x 2 x 2
// of sibling leaves' centres, and the 4 x 4 x 4 and 8 x 8 x 8 of a block of
// leaves' centres) inside the focused region, across its side or wholly
// outside it gives at each point the Vs a model never focused looks up
// there, and the material its at() gives.  The region focused on is a small
// box (its raster cells the finest octants') and, in 24 MB, the large bounds
// box (more finest octants than the raster then holds: its cells are
// coarser, and those holding finer octants of differing Vs are searched).
void expect_lattices_sample_as_lookups(const std::string& model, MemoryBudget memory,
                                       const double focus_lo[3], const double focus_hi[3],
                                       uint64_t seed) {
  std::unique_ptr<DbModel> m, ref;
  ASSERT_TRUE(DbModel::open(model, memory, 1, &m).ok());
  ASSERT_TRUE(DbModel::open(model, MemoryBudget(), 1, &ref).ok());
  std::mt19937_64 rng(seed);
  const auto uniform = [&](double a, double b) {
    return std::uniform_real_distribution<double>(a, b)(rng);
  };
  m->focus(focus_lo, focus_hi);
  int across = 0, inside = 0;
  for (int t = 0; t < 3000; ++t) {
    constexpr int kSizes[5] = {3, 5, 2, 4, 8};  // construct's lattices
    const int n = kSizes[t % 5];
    const double side = std::pow(2.0, uniform(5, 11));
    double axes[3][8];
    bool in = true, out = true;
    for (int a = 0; a < 3; ++a) {
      const double from = uniform(focus_lo[a] - 1500, focus_hi[a] + 500);
      for (int i = 0; i < n; ++i) {
        axes[a][i] = std::clamp(from + side * i / (n - 1), 0.0, a == 2 ? 5599.0 : 7999.0);
        in = in && axes[a][i] >= focus_lo[a] && axes[a][i] <= focus_hi[a];
        out = out && (axes[a][i] < focus_lo[a] || axes[a][i] > focus_hi[a]);
      }
    }
    across += !in && !out;
    inside += in;
    float got[512];
    Material materials[512];
    m->vs_on_lattice(axes[0], axes[1], axes[2], n, got);
    m->materials_on_lattice(axes[0], axes[1], axes[2], n, materials);
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          ModelHit want;
          ASSERT_TRUE(ref->lookup(axes[0][i], axes[1][j], axes[2][k], &want).ok());
          const int at = (k * n + j) * n + i;
          ASSERT_EQ(got[at], want.values[1])
              << "lattice " << t << " at " << axes[0][i] << " " << axes[1][j] << " " << axes[2][k];
          const Material a = ref->at(axes[0][i], axes[1][j], axes[2][k]);
          const Material& b = materials[at];
          ASSERT_TRUE(a.vp == b.vp && a.vs == b.vs && a.rho == b.rho && a.qp == b.qp &&
                      a.qs == b.qs)
              << "materials " << t << " at " << axes[0][i] << " " << axes[1][j] << " "
              << axes[2][k];
        }
  }
  EXPECT_GT(across, 300) << "lattices across the region's side";
  // Wholly inside, a lattice is answered as one (ModelRegion::Lattice).
  EXPECT_GT(inside, 300) << "lattices inside the region";
}

TEST(ModelDb, LatticesAcrossTheRegionsSideSampleAsLookups) {
  const std::string model = import_bounds_model("lattices");
  const double small_lo[3] = {2000, 2000, 1000}, small_hi[3] = {5000, 5000, 3000};
  ASSERT_NO_FATAL_FAILURE(
      expect_lattices_sample_as_lookups(model, MemoryBudget(), small_lo, small_hi, 17));
  ASSERT_NO_FATAL_FAILURE(expect_lattices_sample_as_lookups(model, MemoryBudget(24ull << 20),
                                                            kBoundsFocusLo, kBoundsFocusHi, 18));
}

// The eight halves' bounds at once are eight calls' bounds, bit for bit,
// and say none where a call says none (a half reaching past the focused
// region), for boxes of every size, aligned or not, some halves not asked.
TEST(ModelDb, BoundsOfEighthsAreThoseOfEachEighth) {
  std::unique_ptr<DbModel> m;
  ASSERT_NO_FATAL_FAILURE(open_focused(import_bounds_model("eighths"), &m));
  std::mt19937_64 rng(8);
  const auto uniform = [&](double a, double b) {
    return std::uniform_real_distribution<double>(a, b)(rng);
  };
  int looked = 0, refused = 0;
  for (int n = 0; n < 4000; ++n) {
    const double side = std::pow(2.0, uniform(3, 13));
    double edges[3][3];
    for (int a = 0; a < 3; ++a) {
      const double lo = n % 2 ? std::floor(uniform(0, 8000) / 100) * 100 : uniform(0, 8000);
      edges[a][0] = lo, edges[a][1] = lo + side / 2, edges[a][2] = lo + side;
    }
    bool want[8];
    for (bool& w : want) w = rng() % 4 != 0;
    expect_eighths_as_calls(*m, edges, want, &looked, &refused);
    if (HasFatalFailure()) return;
  }
  EXPECT_GT(looked, 5000);
  EXPECT_GT(refused, 500);
}

// Construct from a model database decides the octants its bounds settle as
// the samples would: the tables, balanced and not, are those of a construct
// that samples every octant, over a domain past the model's box (clamped).
TEST(ModelDb, VsBoundsChangeNoConstructedTable) {
  const std::string model = import_bounds_model("bounds_construct");
  for (bool balanced : {true, false}) {
    std::string tables[2];
    for (int bounds = 0; bounds < 2; ++bounds) {
      ConstructOptions o;
      o.model = "db:" + model;
      o.freq = 1.5;
      o.domain_m = {8800, 8000, 6000};
      o.balanced = balanced;
      o.model_bounds = bounds == 1;
      o.threads = 2;
      ConstructPlan p;
      ConstructResult r;
      const std::string db = fresh("bounds_construct_" + std::to_string(bounds));
      ASSERT_TRUE(construct_octree(db, o, &p, &r).ok());
      EXPECT_GT(r.elements, 10000u);
      tables[bounds] = testing::table_bytes(db);
    }
    ASSERT_EQ(tables[1], tables[0]) << (balanced ? "balanced" : "unbalanced");
  }
}

}  // namespace
}  // namespace weaver
