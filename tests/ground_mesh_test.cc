// Meshes under a ground surface (construct/carve.h): the carved octree is
// 2:1 balanced among the elements that remain (tests/reference's balance
// changes nothing), extraction matches tests/reference's over it, no
// element lies wholly above the ground and every point below it is in an
// element (both judged by the test's own bilinear ground), and solid
// fractions agree with the analytic ones of a plane.  Surfaces: a tilted
// plane, a Gaussian hill, a cliff one leaf wide, a DEM with NODATA holes,
// one whose peak touches the domain's top, and an rfile whose ground dips
// below its first material block's bottom.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "balance/balance.h"
#include "boundary/boundary.h"
#include "cli_run.h"
#include "construct/construct.h"
#include "db/boundary_table.h"
#include "db/database.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "export/export.h"
#include "extract/extract.h"
#include "model/geo_frame.h"
#include "query/explorer.h"
#include "reference/boundary_reference.h"
#include "reference/reference_mesh.h"
#include "rfile_writer.h"
#include "test_mesh.h"
#include "test_util.h"
#include "verify/verify.h"

namespace weaver {
namespace {

constexpr double kGroundSide = 8000, kGroundDepth = 4000;

// A DEM of n x n points over the domain, spacing kGroundSide / (n - 1), written
// as an ESRI raster (cell centres on the points), and the test's own
// bilinear ground over the same points.
struct TestDem {
  int n = 0;
  std::vector<double> z;  // z[i * n + j]: i north (x), j east (y); NaN: NODATA
  double step() const { return kGroundSide / (n - 1); }
  double at(int i, int j) const { return z[size_t(i) * n + j]; }

  void write(const std::string& path) const {
    std::ofstream f(path);
    f << "ncols " << n << "\nnrows " << n << "\nxllcenter 0\nyllcenter 0\ncellsize " << step()
      << "\nnodata_value -9999\n";
    for (int i = n - 1; i >= 0; --i) {  // rows from the north
      for (int j = 0; j < n; ++j) f << (std::isnan(at(i, j)) ? -9999.0 : at(i, j)) << " ";
      f << "\n";
    }
  }
  double ground(double x, double y) const {
    const double u = std::clamp(x / step(), 0.0, n - 1.0), v = std::clamp(y / step(), 0.0, n - 1.0);
    const int i = std::min(int(u), n - 2), j = std::min(int(v), n - 2);
    const double a = u - i, b = v - j;
    return (1 - a) * ((1 - b) * at(i, j) + b * at(i, j + 1)) +
           a * ((1 - b) * at(i + 1, j) + b * at(i + 1, j + 1));
  }
};

TestDem make_test_dem(int n, const std::function<double(double, double)>& g) {
  TestDem d;
  d.n = n;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      d.z.push_back(g(i * kGroundSide / (n - 1), j * kGroundSide / (n - 1)));
  return d;
}

std::vector<std::pair<Octant, float>> leaves_with_solid(const std::string& db_dir) {
  std::vector<std::pair<Octant, float>> out;
  std::unique_ptr<Database> db;
  EXPECT_OK(Database::open(db_dir, Database::Mode::kRead, false, &db));
  std::unique_ptr<BTree> t;
  EXPECT_OK(db->open_table(kOctantTable, 1 << 20, &t));
  const Field* solid = t->options().schema.find("solid");
  EXPECT_NE(solid, nullptr);
  BTreeCursor c;
  EXPECT_OK(t->seek_cursor(0, &c));
  while (c.valid() && solid != nullptr) {
    float f;
    std::memcpy(&f, c.payload() + solid->offset, 4);
    out.push_back({octant_from_key(c.key()), f});
    EXPECT_OK(c.next());
  }
  return out;
}

struct GroundCase {
  std::string name;
  ConstructOptions o;
  std::function<double(double, double)> ground;  // the test's own, metres
  bool plane = false;                            // analytic fractions
};

void check_ground_case(const GroundCase& c, const testing::TempDir& dir) {
  SCOPED_TRACE(c.name);
  const std::string db = dir.file(c.name);
  ConstructPlan plan;
  ConstructResult r;
  ASSERT_OK(construct_octree(db, c.o, &plan, &r));
  ASSERT_TRUE(plan.carved);
  EXPECT_GT(r.air, 0u);
  EXPECT_GT(r.cut, 0u);
  const auto leaves = leaves_with_solid(db);
  ASSERT_EQ(leaves.size(), r.elements);
  std::vector<Octant> octants;
  for (const auto& l : leaves) octants.push_back(l.first);
  // Balanced among what remains.
  EXPECT_TRUE(reference::balance(octants) == octants);
  // Each subtree's balance looks out as far as its elements need (air's
  // own refinement is cut away): the table is the same whatever the
  // subtrees, most visited again as their children.  The ground's leaves
  // made fine, so that the balance grades the solid below them and splits
  // the air beside them.
  {
    ConstructOptions fine = c.o;
    fine.surface_edge_m = 70;
    std::string tables[2];
    for (int small = 0; small < 2; ++small) {
      fine.subtree_leaves = small ? 64 : 0;
      ConstructPlan fp;
      ConstructResult fr;
      const std::string fine_db = dir.file(c.name + "-fine" + std::to_string(small));
      ASSERT_OK(construct_octree(fine_db, fine, &fp, &fr));
      EXPECT_GT(fr.elements + fr.air, fr.descended);  // the balance split leaves
      if (small) {
        EXPECT_GT(fr.subtrees_over, 0u);
      }
      tables[small] = testing::table_bytes(fine_db);
    }
    EXPECT_TRUE(tables[1] == tables[0]);
    // weaver balance of the unbalanced carved table carves what it splits:
    // no new leaf of air, each new leaf's fraction its own.
    fine.subtree_leaves = 0;
    fine.balanced = false;
    ConstructPlan up;
    ConstructResult ur;
    const std::string unbalanced = dir.file(c.name + "-unbalanced");
    ASSERT_OK(construct_octree(unbalanced, fine, &up, &ur));
    BalanceResult br;
    ASSERT_OK(balance_octree(unbalanced, BalanceOptions{}, &br));
    const auto balanced = leaves_with_solid(unbalanced);
    EXPECT_GT(balanced.size(), ur.elements);
    for (const auto& [o, f] : balanced) {
      const double e = octant_edge(o) * up.tick_m;
      const double lo[3] = {o.x * up.tick_m, o.y * up.tick_m, o.z * up.tick_m};
      const double hi[3] = {lo[0] + e, lo[1] + e, lo[2] + e};
      ASSERT_EQ(f, static_cast<float>(solid_fraction(up.ground, lo, hi)))
          << o.x << " " << o.y << " " << o.z << " level " << int(o.level);
    }
  }
  const double t = plan.tick_m, top = plan.ground.top_elevation;
  // No element wholly above the ground: some point of its footprint (a
  // fine lattice, corners included) has ground above its bottom.
  uint64_t cut = 0;
  for (const auto& [o, f] : leaves) {
    ASSERT_GT(f, 0.0f);
    ASSERT_LE(f, 1.0f);
    const double e = octant_edge(o) * t, x0 = o.x * t, y0 = o.y * t,
                 bottom = (o.z + octant_edge(o)) * t;
    double highest = -HUGE_VAL;
    for (int i = 0; i <= 16; ++i)
      for (int j = 0; j <= 16; ++j)
        highest = std::max(highest, c.ground(x0 + e * i / 16, y0 + e * j / 16));
    // The lattice may miss the very top of the ground by its slope times
    // a sixteenth of the edge: an eighth of the edge is let be.
    ASSERT_GT(bottom + e / 8, top - highest)
        << o.x << " " << o.y << " " << o.z << " level " << int(o.level);
    (void)highest;
    if (f < 1) ++cut;
    if (c.plane && f < 1) {
      // A plane across the whole footprint, within the leaf's height: the
      // fraction is the share of the height below the mean ground.
      const double z_top = o.z * t, z_bottom = bottom;
      const double g_centre = top - c.ground(x0 + e / 2, y0 + e / 2);
      double lo = HUGE_VAL, hi = -HUGE_VAL;
      for (double dx : {0.0, e})
        for (double dy : {0.0, e}) {
          const double g = top - c.ground(x0 + dx, y0 + dy);
          lo = std::min(lo, g), hi = std::max(hi, g);
        }
      if (lo >= z_top && hi <= z_bottom) {
        EXPECT_NEAR(f, (z_bottom - g_centre) / e, 1e-4) << o.x << " " << o.y << " " << o.z;
      }
    }
  }
  EXPECT_EQ(cut, r.cut);
  // Every point below the ground lies in an element.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, kGroundSide), w(0, kGroundDepth);
  int below = 0;
  for (int n = 0; n < 3000; ++n) {
    const double x = u(rng), y = u(rng), z = w(rng);
    if (top - z >= c.ground(x, y) - 1e-6) continue;
    ++below;
    const Coord p{uint32_t(x / t), uint32_t(y / t), uint32_t(z / t)};
    // The leaf holding p is the last one at or before p's pixel in key order.
    const uint64_t key = octant_key(Octant{p.x, p.y, p.z, kMaxLevel});
    auto it = std::upper_bound(octants.begin(), octants.end(), key,
                               [](uint64_t k, const Octant& o) { return k < octant_key(o); });
    ASSERT_TRUE(it != octants.begin() && octant_contains_point(*(it - 1), p))
        << x << " " << y << " " << z;
  }
  EXPECT_GT(below, 100);
  // Extraction over the carved octree, against the reference.
  ExtractResult er;
  ASSERT_OK(extract_mesh(db, ExtractOptions{}, &er));
  const reference::Mesh ref = reference::extract(octants);
  ASSERT_EQ(er.nodes, ref.nodes.size());
  std::unique_ptr<Database> d;
  ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &d));
  std::unique_ptr<BTree> nodes;
  ASSERT_OK(d->open_table(kNodeTable, 1 << 20, &nodes));
  BTreeCursor cur;
  ASSERT_OK(nodes->seek_cursor(0, &cur));
  for (const reference::MeshNode& want : ref.nodes) {
    ASSERT_TRUE(cur.valid());
    ASSERT_EQ(morton_decode(cur.key()), want.c);
    ASSERT_EQ(static_cast<NodeKind>(cur.payload()[0]), want.kind);
    ASSERT_OK(cur.next());
  }
  // locate: a point above the ground is in a cut element or, where none
  // holds it, in the air; one beside the domain is not in the air.
  {
    std::unique_ptr<Explorer> ex;
    ASSERT_OK(Explorer::open(db, MemoryBudget(16 << 20), &ex));
    int air = 0;
    for (int n = 0; n < 400; ++n) {
      const double x = u(rng), y = u(rng), z = w(rng);
      const Coord p{uint32_t(x / t), uint32_t(y / t), uint32_t(z / t)};
      PointHit h;
      ASSERT_OK(ex->locate(p, &h));
      const bool above = top - z > c.ground(x, y) + 1e-6;
      if (!above) continue;
      if (h.inside) continue;  // a cut element reaches above the ground here
      ASSERT_TRUE(ex->in_air(p)) << x << " " << y << " " << z;
      ++air;
    }
    EXPECT_GT(air, 0);
    EXPECT_FALSE(ex->in_air({uint32_t((kGroundSide + 500) / t), 0, 0}));
  }
  // The boundary table, the ground ruling out the buried elements, against
  // the reference's from the leaves alone.
  BoundaryResult br;
  ASSERT_OK(build_boundary(db, BoundaryOptions{}, &br));
  EXPECT_FALSE(br.filled);
  EXPECT_LT(br.asked, leaves.size());
  // The least edge / vp, found by construct's workers and by the boundary's
  // scan alike, is the least of every leaf's; the same on three threads
  // (runs of the elements, the later ones cut short to 5 records held).
  EXPECT_EQ(br.least_dt, r.least_dt);
  EXPECT_EQ(br.least_dt_element, r.least_dt_element);
  {
    BoundaryOptions three;
    three.threads = 3, three.held_records = 5;
    BoundaryResult br3;
    ASSERT_OK(build_boundary(db, three, &br3));
    EXPECT_EQ(br3.least_dt, r.least_dt);
    EXPECT_EQ(br3.least_dt_element, r.least_dt_element);
    EXPECT_EQ(br3.faces, br.faces);
    EXPECT_EQ(br3.asked, br.asked);
  }
  {
    const auto want = reference::boundary(octants);
    std::unique_ptr<Database> bd;
    ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &bd));
    std::unique_ptr<BTree> bt;
    ASSERT_OK(bd->open_table(kBoundaryTable, 1 << 20, &bt));
    ASSERT_EQ(bt->size(), want.size());
    BTreeCursor bc;
    ASSERT_OK(bt->seek_cursor(0, &bc));
    for (const auto& w : want) {
      ASSERT_EQ(bc.key(), boundary_key(w.element, w.face, w.part));
      ASSERT_EQ(int(static_cast<uint8_t>(bc.payload()[0])), w.kind);
      ASSERT_OK(bc.next());
    }
  }
  // The raw export carries each element's fraction, and the top's elevation.
  ExportOptions eo;
  eo.format = ExportFormat::kRaw;
  eo.out = dir.file(c.name + "-raw");
  ExportResult xr;
  ASSERT_OK(export_mesh(db, eo, &xr));
  std::ifstream json_in(eo.out + "/mesh.json");
  const std::string json((std::istreambuf_iterator<char>(json_in)),
                         std::istreambuf_iterator<char>());
  const size_t at = json.find("\"element_solid_fraction\"");
  ASSERT_NE(at, std::string::npos);
  const size_t off = json.find("\"offset\": ", at);
  ASSERT_NE(off, std::string::npos);
  const uint64_t offset = std::stoull(json.substr(off + 10));
  EXPECT_NE(json.find("\"top_elevation_m\": "), std::string::npos);
  std::ifstream bin(eo.out + "/mesh.bin", std::ios::binary);
  bin.seekg(std::streamoff(offset));
  for (const auto& [o, f] : leaves) {
    float got = 0;
    bin.read(reinterpret_cast<char*>(&got), 4);
    ASSERT_EQ(got, f) << o.x << " " << o.y << " " << o.z;
  }
  VerifyOptions vo;
  VerifyReport report;
  ASSERT_OK(verify_database(db, vo, &report));
  EXPECT_TRUE(report.ok()) << (report.problems.empty() ? "" : report.problems[0]);
}

ConstructOptions ground_options_for(const std::string& surface) {
  ConstructOptions o;
  o.model = "loh1";
  o.freq = testing::small_scale() ? 0.4 : 0.6;
  o.domain_m = {kGroundSide, kGroundSide, kGroundDepth};
  o.surface = surface;
  o.memory = MemoryBudget(64ull << 20);
  o.threads = 2;
  return o;
}

TEST(GroundMesh, CarvedOctreesAreBalancedCompleteAndExtractAsTheReference) {
  testing::TempDir dir;
  std::vector<GroundCase> cases;
  auto ground_dem_case = [&](const std::string& name, int n,
                             std::function<double(double, double)> g, bool plane = false) {
    const TestDem d = make_test_dem(n, g);
    const std::string path = dir.file(name + ".asc");
    d.write(path);
    GroundCase c{name, ground_options_for("asc:" + path),
                 [d](double x, double y) { return d.ground(x, y); }, plane};
    cases.push_back(c);
    return &cases.back();
  };
  ground_dem_case(
      "plane", 9, [](double x, double y) { return 300 + 0.1 * x + 0.05 * y; }, true);
  ground_dem_case("hill", 41, [](double x, double y) {
    return 1500 *
           std::exp(-((x - 3000) * (x - 3000) + (y - 5000) * (y - 5000)) / (2 * 1200.0 * 1200));
  });
  // A cliff of 400 m across one 50 m cell, narrower than the 125 m leaves
  // --surface-edge 150 asks for along the ground.
  GroundCase* cliff =
      ground_dem_case("cliff", 161, [](double, double y) { return y < 4000 ? 600.0 : 200.0; });
  cliff->o.surface_edge_m = 150;
  // Holes of NODATA, each among valid neighbours that all hold the hole's
  // own value: whichever of them the fill takes, the ground is the one the
  // test computes with the holes filled.
  {
    TestDem d = make_test_dem(
        17, [](double x, double y) { return 900 + 800 * std::sin(x / 1500) * std::cos(y / 2000); });
    const int holes[3][2] = {{5, 5}, {5, 6}, {12, 3}};
    for (const auto& h : holes) {
      const double v = d.at(h[0], h[1]);
      for (const auto& n : {std::array<int, 2>{h[0] - 1, h[1]},
                            {h[0] + 1, h[1]},
                            {h[0], h[1] - 1},
                            {h[0], h[1] + 1}}) {
        const bool hole = (n[0] == 5 && (n[1] == 5 || n[1] == 6)) || (n[0] == 12 && n[1] == 3);
        if (!hole) d.z[size_t(n[0]) * 17 + n[1]] = v;
      }
    }
    const TestDem filled = d;
    for (const auto& h : holes) d.z[size_t(h[0]) * 17 + h[1]] = NAN;
    const std::string path = dir.file("holes.asc");
    d.write(path);
    cases.push_back({"holes", ground_options_for("asc:" + path),
                     [filled](double x, double y) { return filled.ground(x, y); }});
  }
  // The top set at the peak itself: the ground touches z = 0.
  GroundCase* touch =
      ground_dem_case("touch", 9, [](double x, double) { return x >= 4000 ? 1000.0 : 200.0; });
  touch->o.top_elevation = 1000;
  for (const GroundCase& c : cases) ASSERT_NO_FATAL_FAILURE(check_ground_case(c, dir));
}

TEST(GroundMesh, AnRfileBringsItsOwnGroundAndItsBlocksBeneath) {
  testing::TempDir dir;
  // Topography 0 to 1200 m; block 1 from -1500 m (above the peak) down to
  // 500 m, block 2 below: the ground dips under block 1's bottom in the
  // west (elevation -700 m, z 700 m below sea level).
  std::vector<Block> b;
  b.push_back({200, 200, 0, 1, 41, 41, 1, [](int i, int j, int) {
                 return std::vector<double>{i < 10 ? -700.0 : 1200.0 * j / 40};
               }});
  b.push_back({100, 50, -1500, 3, 81, 81, 41, [](int, int, int k) {
                 return std::vector<double>{2000, 1500 + 10.0 * k, 600 + 5.0 * k};
               }});
  b.push_back({400, 400, 500, 3, 21, 21, 11, [](int, int, int k) {
                 return std::vector<double>{2500, 5000 + 10.0 * k, 2800 + 5.0 * k};
               }});
  RfileWriter w;
  const std::string path = dir.file("model.rfile");
  std::ofstream(path, std::ios::binary) << w.bytes(b);
  GroundCase c{"rfile", ground_options_for(""), nullptr};
  c.o.model = "rfile:" + path;
  c.o.freq = testing::small_scale() ? 0.2 : 0.3;
  auto topo = b[0].value;
  c.ground = [topo](double x, double y) {
    const double u = std::clamp(x / 200, 0.0, 40.0), v = std::clamp(y / 200, 0.0, 40.0);
    const int i = std::min(int(u), 39), j = std::min(int(v), 39);
    const double a = u - i, bb = v - j;
    auto g = [&](int p, int q) { return topo(p, q, 0)[0]; };
    return (1 - a) * ((1 - bb) * g(i, j) + bb * g(i, j + 1)) +
           a * ((1 - bb) * g(i + 1, j) + bb * g(i + 1, j + 1));
  };
  ASSERT_NO_FATAL_FAILURE(check_ground_case(c, dir));
  // The file's Vs bounds (RfileVsTiles) change nothing but the samples taken.
  {
    std::string tables[2];
    for (int bounds = 0; bounds < 2; ++bounds) {
      ConstructOptions o = c.o;
      o.model_bounds = bounds == 1;
      ConstructPlan p;
      ConstructResult r;
      const std::string db = dir.file("bounds" + std::to_string(bounds));
      ASSERT_OK(construct_octree(db, o, &p, &r));
      tables[bounds] = testing::table_bytes(db);
    }
    EXPECT_FALSE(tables[0].empty());
    EXPECT_TRUE(tables[1] == tables[0]);
  }
  // The plan: the rfile's ground, its z read as depth below sea level, the
  // top at the highest ground rounded up to a tick.
  ConstructPlan plan;
  ASSERT_OK(plan_construct(c.o, &plan));
  EXPECT_EQ(plan.surface_source, c.o.model);
  EXPECT_EQ(plan.ground.model_z, ModelZ::kElevation);
  EXPECT_GE(plan.ground.top_elevation, 1200);
  EXPECT_LT(plan.ground.top_elevation, 1200 + plan.tick_m);
  // --surface flat: no carving, the rfile read with z = 0 at sea level.
  c.o.surface = "flat";
  ASSERT_OK(plan_construct(c.o, &plan));
  EXPECT_FALSE(plan.carved);
  EXPECT_EQ(plan.ground.top_elevation, 0);
  // A top below the ground is refused before anything is written.
  c.o.surface = "";
  c.o.top_elevation = 1000;
  const Status st = plan_construct(c.o, &plan);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("above --top-elevation"), std::string::npos) << st.message();
}

}  // namespace
}  // namespace weaver

namespace weaver {
namespace {

// A mesh (construct, extract) under the DEM of `ground` written to `dem`;
// its database's path.
std::string mesh_under(const testing::TempDir& dir, const std::string& dem,
                       const std::function<double(double, double)>& ground, ConstructPlan* plan) {
  make_test_dem(9, ground).write(dem);
  const std::string db = dir.file("db");
  ConstructResult r;
  EXPECT_OK(construct_octree(db, ground_options_for("asc:" + dem), plan, &r));
  ExtractResult er;
  EXPECT_OK(extract_mesh(db, ExtractOptions{}, &er));
  return db;
}

TEST(GroundMesh, VerifyFindsElementsAboveTheGroundItWasBuiltUnder) {
  testing::TempDir dir;
  const std::string dem = dir.file("hill.asc");
  ConstructPlan plan;
  const std::string db = mesh_under(
      dir, dem, [](double x, double) { return 200 + 0.2 * x; }, &plan);
  VerifyReport report;
  ASSERT_OK(verify_database(db, VerifyOptions{}, &report));
  EXPECT_TRUE(report.ok()) << report.problems[0];
  // The ground the metadata names, lowered by 1 km: the top elements of the
  // mountain side now stand in the air.
  make_test_dem(9, [](double x, double) { return -800 + 0.2 * x; }).write(dem);
  ASSERT_OK(verify_database(db, VerifyOptions{}, &report));
  ASSERT_FALSE(report.ok());
  EXPECT_NE(report.problems[0].find("lies wholly above the ground"), std::string::npos)
      << report.problems[0];
  std::filesystem::remove(dem);
  ASSERT_OK(verify_database(db, VerifyOptions{}, &report));
  ASSERT_FALSE(report.ok());
  EXPECT_NE(report.problems[0].find("cannot be read again"), std::string::npos)
      << report.problems[0];
}

}  // namespace
}  // namespace weaver

namespace weaver {
namespace {

// Queries take z as the domain's depth, as elevation or as depth below the
// local ground: the three name the same point.
TEST(GroundMesh, QueriesTakeElevationAndDepthBelowTheGround) {
  testing::TempDir dir;
  const std::string dem = dir.file("plane.asc");
  auto ground = [](double x, double y) { return 300 + 0.1 * x + 0.05 * y; };
  ConstructPlan plan;
  const std::string db = mesh_under(dir, dem, ground, &plan);
  const double top = plan.ground.top_elevation, x = 3000, y = 5000, depth = 700;
  const double z = top - ground(x, y) + depth;
  auto row = [&](const std::string& point, const std::string& mode) {
    const testing::CommandRun q =
        testing::run("query " + db + " locate " + point + " --units m --format csv --z " + mode);
    EXPECT_EQ(q.code, 0) << q.err;
    return q.out.substr(q.out.find('\n') + 1);
  };
  char domain[96], elevation[96], below[96];
  std::snprintf(domain, sizeof domain, "%.17g %.17g %.17g", x, y, z);
  std::snprintf(elevation, sizeof elevation, "%.17g %.17g %.17g", x, y, ground(x, y) - depth);
  std::snprintf(below, sizeof below, "%.17g %.17g %.17g", x, y, depth);
  const std::string want = row(domain, "domain");
  EXPECT_NE(want.find(",inside,"), std::string::npos) << want;
  // The element and its material agree (the z column is the domain's).
  auto tail = [](const std::string& s) { return s.substr(s.find(",inside,")); };
  EXPECT_EQ(tail(row(elevation, "elevation")), tail(want));
  EXPECT_EQ(tail(row(below, "depth")), tail(want));
  // 600 m above the ground, past any cut element's reach: the air.
  std::snprintf(elevation, sizeof elevation, "%.17g %.17g %.17g", x, y, ground(x, y) + 600);
  EXPECT_NE(row(elevation, "elevation").find(",air,"), std::string::npos);
}

}  // namespace
}  // namespace weaver

namespace weaver {
namespace {

// A DEM that misses part of the domain: said in the plan, refused with
// --outside error; NODATA likewise.  A raster in degrees (--surface-crs
// lonlat) resampled through the mesh's frame puts the ground where its own
// longitude and latitude say.
TEST(GroundMesh, SurfacesOutsideTheDomainOrInDegrees) {
  testing::TempDir dir;
  const std::string small = dir.file("small.asc");
  {
    std::ofstream f(small);  // 4 km x 4 km of an 8 km domain
    f << "ncols 3\nnrows 3\nxllcenter 0\nyllcenter 0\ncellsize 2000\n";
    for (int r = 0; r < 3; ++r) f << "100 200 300\n";
  }
  ConstructOptions o = ground_options_for("asc:" + small);
  ConstructPlan plan;
  ASSERT_OK(plan_construct(o, &plan));
  EXPECT_NE(plan.surface_outside.find("x+, y+"), std::string::npos) << plan.surface_outside;
  o.outside_error = true;
  const Status refused = plan_construct(o, &plan);
  EXPECT_FALSE(refused.ok());
  EXPECT_NE(refused.message().find("does not cover"), std::string::npos) << refused.message();
  // In degrees: a raster 0.2 degrees a side around the origin, its ground
  // rising 1 m per 0.001 degree of longitude (east).
  const std::string deg = dir.file("deg.asc");
  {
    std::ofstream f(deg);
    f << "ncols 201\nnrows 201\nxllcenter -118.1\nyllcenter 33.9\ncellsize 0.001\n";
    for (int r = 200; r >= 0; --r) {
      for (int c = 0; c <= 200; ++c) f << 500 + c << " ";
      f << "\n";
    }
  }
  ConstructOptions d = ground_options_for("asc:" + deg);
  d.geo = "-118,34,0";
  d.surface_crs = SurfaceCrs::kLonLat;
  ASSERT_OK(plan_construct(d, &plan));
  ASSERT_TRUE(plan.carved);
  GeoFrame g;
  ASSERT_OK(GeoFrame::parse("-118,34,0", &g));
  for (double x : {500.0, 4000.0, 7500.0}) {
    for (double y : {500.0, 4000.0, 7500.0}) {
      double lon, lat;
      g.to_geo(x, y, &lon, &lat);
      const double want = 500 + (lon + 118.1) / 0.001;
      // Resampled at the raster's own spacing (111 m north): within the
      // ground's change over a cell of it.
      EXPECT_NEAR(plan.surface->elevation(x, y), want, 1.5) << x << " " << y;
    }
  }
}

}  // namespace
}  // namespace weaver
