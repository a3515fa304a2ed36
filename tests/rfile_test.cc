// SW4 rfiles (model/rfile.h, model/rfile_model.h) and the ground surface
// (model/surface.h), against the test's own writer and independent
// arithmetic: linear fields (which trilinear sampling reproduces exactly),
// SW4's fill rule worked by hand, and brute-force ranges.
#include "model/rfile.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "model/rfile_model.h"
#include "model/surface.h"
#include "modeldb/db_model.h"
#include "modeldb/model_import.h"
#include "rfile_writer.h"
#include "test_util.h"

namespace weaver {
namespace {

void write_file(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// Per block a linear field: trilinear sampling gives it back exactly.
double field(int block, int c, double x, double y, double z) {
  return 1000 + 100 * block + 10 * c + 0.01 * x + 0.02 * y + 0.05 * z;
}

std::vector<Block> linear_blocks() {
  std::vector<Block> b;
  b.push_back({30, 30, 0, 1, 11, 7, 1,
               [](int i, int j, int) { return std::vector<double>{100 + i * 3.0 + j}; }});
  // hh 30 m, hv 25 m: spans 300 x 180 m, z -200 .. 100.  Then hh 60,
  // hv 70 (no power-of-two part of anything), z 100 .. 1500.
  const double hh[3] = {0, 30, 60}, hv[3] = {0, 25, 70}, z0[3] = {0, -200, 100};
  const int ni[3] = {0, 11, 6}, nj[3] = {0, 7, 4}, nk[3] = {0, 13, 21};
  for (int k = 1; k <= 2; ++k) {
    b.push_back({hh[k], hv[k], z0[k], 5, ni[k], nj[k], nk[k], [=](int i, int j, int l) {
                   std::vector<double> v;
                   for (int c = 0; c < 5; ++c)
                     v.push_back(field(k, c, i * hh[k], j * hh[k], z0[k] + l * hv[k]));
                   return v;
                 }});
  }
  return b;
}

Status open_bytes(const testing::TempDir& dir, const std::string& bytes,
                  std::unique_ptr<RfileModel>* m) {
  const std::string path = dir.file("m.rfile");
  write_file(path, bytes);
  return RfileModel::open(path, MemoryBudget(1 << 20), 1, m);
}

// linear_blocks with no data (-999 Vs) in block 1 where hole(i, j, k).
std::vector<Block> blocks_with_holes(std::function<bool(int, int, int)> hole) {
  std::vector<Block> b = linear_blocks();
  const auto base = b[1].value;
  b[1].value = [base, hole](int i, int j, int k) {
    std::vector<double> v = base(i, j, k);
    if (hole(i, j, k)) v[2] = -999;
    return v;
  };
  return b;
}

TEST(Rfile, SamplesLinearFieldsExactlyInTheBlockSw4Picks) {
  testing::TempDir dir;
  for (bool big : {false, true}) {
    for (int precision : {4, 8}) {
      RfileWriter w;
      w.big_endian = big, w.precision = precision;
      std::unique_ptr<RfileModel> m;
      ASSERT_OK(open_bytes(dir, w.bytes(linear_blocks()), &m));
      EXPECT_TRUE(m->has_q());
      EXPECT_EQ(m->header().proj, "+proj=utm +zone=11");
      EXPECT_EQ(m->header().swap, big);
      EXPECT_DOUBLE_EQ(m->x_extent(), 300);
      EXPECT_DOUBLE_EQ(m->y_extent(), 180);
      std::mt19937 rng(precision + big);
      std::uniform_real_distribution<double> ux(0, 300), uy(0, 180), uz(-200, 1500);
      for (int n = 0; n < 2000; ++n) {
        const double x = ux(rng), y = uy(rng), z = uz(rng);
        // SW4: block 2 from its top z0 = 100 down, block 1 above.
        const int b = z >= 100 ? 2 : 1;
        const Material got = m->at(x, y, z);
        ASSERT_EQ(m->vs_at(x, y, z), got.vs);  // the Vs-only path, to the bit
        const double tol = precision == 4 ? 2e-3 : 1e-3;
        ASSERT_NEAR(got.rho, field(b, 0, x, y, z), tol * 5) << x << " " << y << " " << z;
        ASSERT_NEAR(got.vp, field(b, 1, x, y, z), tol * 5);
        ASSERT_NEAR(got.vs, field(b, 2, x, y, z), tol * 5);
        ASSERT_NEAR(got.qp, field(b, 3, x, y, z), tol * 5);
        ASSERT_NEAR(got.qs, field(b, 4, x, y, z), tol * 5);
      }
      // Outside the box: the nearest point of it.
      EXPECT_NEAR(m->at(-50, 500, -900).vs, field(1, 2, 0, 180, -200), 0.01);
      EXPECT_NEAR(m->at(400, -5, 9000).vs, field(2, 2, 300, 0, 1500), 0.01);
    }
  }
}

TEST(Rfile, NoDataTakesTheFirstValidValueBelowAsSw4Fills) {
  testing::TempDir dir;
  // Block 1: -999 above level 4 in column (2, 3); everything -999 in (5, 5).
  // Block 2 has valid values everywhere.
  const std::vector<Block> b = blocks_with_holes(
      [](int i, int j, int k) { return (i == 2 && j == 3 && k < 4) || (i == 5 && j == 5); });
  RfileWriter w;
  std::unique_ptr<RfileModel> m;
  ASSERT_OK(open_bytes(dir, w.bytes(b), &m));
  // Grid point (2, 3, 1) takes level 4's values (all five fields).
  const double x = 2 * 30, y = 3 * 30;
  const Material got = m->at(x, y, -200 + 1 * 25);
  EXPECT_NEAR(got.vs, field(1, 2, x, y, -200 + 4 * 25), 1e-3);
  EXPECT_NEAR(got.rho, field(1, 0, x, y, -200 + 4 * 25), 1e-3);
  // Column (5, 5) of block 1 takes block 2's top at (trunc(150 / 60),
  // trunc(150 / 60)) = (2, 2), at every level.
  const Material whole = m->at(150, 150, -100);
  EXPECT_NEAR(whole.vs, field(2, 2, 120, 120, 100), 1e-3);
  // Block 2 has a column with no data at all: nothing to fill from.
  std::vector<Block> bad = linear_blocks();
  const auto base2 = bad[2].value;
  bad[2].value = [base2](int i, int j, int k) {
    std::vector<double> v = base2(i, j, k);
    if (i == 1 && j == 1) v[2] = -999;
    return v;
  };
  const Status st = open_bytes(dir, w.bytes(bad), &m);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("i=1 j=1"), std::string::npos) << st.message();
}

// lattice_at (model import's path) against at(), point by point, to the
// bit: lattices across both blocks, past the box, over filled -999 columns,
// with a cache small enough to lose columns between lookups.
// linear_blocks with holes in some columns, written at `precision`.
std::string holed_rfile(const testing::TempDir& dir, int precision) {
  const std::vector<Block> b = blocks_with_holes([](int i, int j, int k) {
    return (i == 2 && j == 3 && k < 4) || (i == 5 && j == 5) || (i == 9 && k < 7);
  });
  RfileWriter w;
  w.precision = precision;
  const std::string path = dir.file("holed-" + std::to_string(precision) + ".rfile");
  write_file(path, w.bytes(b));
  return path;
}

TEST(Rfile, LatticeGivesWhatAtGivesToTheBit) {
  testing::TempDir dir;
  for (int precision : {4, 8}) {
    const std::string path = holed_rfile(dir, precision);
    std::unique_ptr<RfileModel> m;
    ASSERT_OK(RfileModel::open(path, MemoryBudget(64 << 10), 1, &m));
    std::mt19937 rng(precision);
    std::uniform_real_distribution<double> ux(-20, 320), uy(-20, 200), uz(-260, 1600);
    std::uniform_int_distribution<int> count(1, 9);
    for (int n = 0; n < 300; ++n) {
      std::vector<double> axis[3];
      for (int a = 0; a < 3; ++a) {
        axis[a].resize(count(rng));
        for (double& v : axis[a]) v = a == 0 ? ux(rng) : a == 1 ? uy(rng) : uz(rng);
        std::sort(axis[a].begin(), axis[a].end());
      }
      const int nx = int(axis[0].size()), ny = int(axis[1].size()), nz = int(axis[2].size());
      std::vector<Material> got(size_t(nx) * ny * nz);
      m->lattice_at(axis[0].data(), nx, axis[1].data(), ny, axis[2].data(), nz, got.data());
      for (int c = 0; c < nz; ++c) {
        for (int y = 0; y < ny; ++y) {
          for (int x = 0; x < nx; ++x) {
            const Material want = m->at(axis[0][x], axis[1][y], axis[2][c]);
            const Material& g = got[(size_t(c) * ny + y) * nx + x];
            ASSERT_EQ(std::memcmp(&g, &want, sizeof want), 0)
                << axis[0][x] << " " << axis[1][y] << " " << axis[2][c] << ": vs " << g.vs
                << " against " << want.vs;
          }
        }
      }
    }
    ASSERT_OK(m->error());
  }
}

// Construct's lattices (vs_on_lattice) and a grounded model's columns of
// their own depths (vs_on_columns) give vs_at's Vs to the bit: over holes,
// past the box, across blocks within a column, and with caches so small
// that a cell's four columns evict one another.
TEST(Rfile, ColumnsGiveWhatVsAtGivesToTheBit) {
  testing::TempDir dir;
  for (int precision : {4, 8}) {
    const std::string path = holed_rfile(dir, precision);
    for (const uint64_t cache : {uint64_t{2} << 10, uint64_t{64} << 10}) {
      std::unique_ptr<RfileModel> m;
      ASSERT_OK(RfileModel::open(path, MemoryBudget(cache), 1, &m));
      std::mt19937 rng(precision + int(cache));
      std::uniform_real_distribution<double> ux(-20, 320), uy(-20, 200), uz(-260, 1600);
      for (int t = 0; t < 400; ++t) {
        const int n = t % 2 == 0 ? 3 : 5;
        double xs[5], ys[5], zs[5], columns[125];
        for (int i = 0; i < n; ++i) xs[i] = ux(rng), ys[i] = uy(rng), zs[i] = uz(rng);
        std::sort(zs, zs + n);
        for (double& z : columns) z = uz(rng);
        float lattice[125], own[125];
        m->vs_on_lattice(xs, ys, zs, n, lattice);
        m->vs_on_columns(xs, ys, columns, n, own);
        for (int k = 0; k < n; ++k)
          for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
              const int p = (k * n + j) * n + i;
              ASSERT_EQ(lattice[p], m->vs_at(xs[i], ys[j], zs[k])) << xs[i] << " " << ys[j];
              ASSERT_EQ(lattice[p], m->at(xs[i], ys[j], zs[k]).vs);
              ASSERT_EQ(own[p], m->vs_at(xs[i], ys[j], columns[(j * n + i) * n + k]))
                  << xs[i] << " " << ys[j] << " " << columns[(j * n + i) * n + k];
            }
      }
      ASSERT_OK(m->error());
    }
  }
}

// vs_bounds (RfileVsTiles) holds every Vs at() gives in the box: boxes
// across both blocks, past the file's box, over filled holes, of one cell
// and of many; and a small box's bounds are narrower than the file's range.
TEST(Rfile, VsBoundsHoldEverySampleOfTheBox) {
  testing::TempDir dir;
  for (int precision : {4, 8}) {
    std::unique_ptr<RfileModel> m;
    ASSERT_OK(RfileModel::open(holed_rfile(dir, precision), MemoryBudget(8 << 10), 1, &m));
    std::mt19937 rng(precision);
    std::uniform_real_distribution<double> ux(-40, 320), uy(-40, 200), uz(-300, 1600), u(0, 1);
    std::uniform_real_distribution<double> edge(1, 400);
    int narrow = 0, said = 0;
    float all_lo = HUGE_VALF, all_hi = -HUGE_VALF;
    const double everything[2][3] = {{-1e6, -1e6, -1e6}, {1e6, 1e6, 1e6}};
    ASSERT_TRUE(m->vs_bounds(everything[0], everything[1], &all_lo, &all_hi));
    for (int t = 0; t < 400; ++t) {
      const double e = edge(rng);
      const double lo[3] = {ux(rng), uy(rng), uz(rng)};
      const double hi[3] = {lo[0] + e, lo[1] + e, lo[2] + e};
      float vs_lo, vs_hi;
      if (!m->vs_bounds(lo, hi, &vs_lo, &vs_hi)) continue;
      ++said;
      narrow += vs_hi - vs_lo < all_hi - all_lo;
      for (int n = 0; n < 300; ++n) {
        // The corners, then points inside.
        const double x = n < 8 ? (n & 1 ? hi[0] : lo[0]) : lo[0] + u(rng) * e;
        const double y = n < 8 ? (n & 2 ? hi[1] : lo[1]) : lo[1] + u(rng) * e;
        const double z = n < 8 ? (n & 4 ? hi[2] : lo[2]) : lo[2] + u(rng) * e;
        const float vs = m->vs_at(x, y, z);
        ASSERT_GE(vs, vs_lo) << x << " " << y << " " << z;
        ASSERT_LE(vs, vs_hi) << x << " " << y << " " << z;
      }
    }
    EXPECT_GT(said, 300);
    EXPECT_GT(narrow, 100);
    ASSERT_OK(m->error());
  }
}

TEST(Rfile, RefusesDamagedTruncatedAndLyingFiles) {
  testing::TempDir dir;
  RfileWriter w;
  const std::string good = w.bytes(linear_blocks());
  std::unique_ptr<RfileModel> m;
  ASSERT_OK(open_bytes(dir, good, &m));
  auto refused = [&](std::string bytes, const char* says) {
    const Status st = open_bytes(dir, bytes, &m);
    ASSERT_FALSE(st.ok()) << says;
    EXPECT_NE(st.message().find(says), std::string::npos) << st.message();
    EXPECT_EQ(st.message().find('\n'), std::string::npos);
  };
  const auto set_i32 = [](std::string s, size_t at, int32_t v) {
    std::memcpy(&s[at], &v, 4);
    return s;
  };
  const size_t blocks_at = 12 + 24 + 4 + w.proj.size();
  refused(set_i32(good, 0, 7), "not an rfile");
  refused(set_i32(good, 4, 3), "precision 3");
  refused(set_i32(good, 8, 2), "attenuation flag 2");
  refused(set_i32(good, blocks_at, 0), "0 blocks");
  refused(set_i32(good, 36, -5), "PROJ string of -5");
  // Block 2's ni (4 + 24 + 4 bytes into its header) negative, and huge.
  const size_t block2 = blocks_at + 4 + 40 + 40;
  refused(set_i32(good, block2 + 28, -11), "count -11");
  refused(set_i32(good, block2 + 28, 1 << 30), "runs past the end");
  refused(good.substr(0, good.size() - 3), "runs past the end");
  refused(good.substr(0, 20), "truncated");
  refused(good + "xx", "2 bytes after the last block");
  std::vector<Block> b = linear_blocks();
  b[2].ni = 7;  // 360 m, not 300
  refused(w.bytes(b), "they must agree");
  b = linear_blocks();
  b[2].z0 = 150;  // block 1 ends at 100
  refused(w.bytes(b), "without a gap");
  b = linear_blocks();
  std::swap(b[1], b[2]);
  refused(w.bytes(b), "stacked top to bottom");
  w.attenuation = 0;
  refused(w.bytes(linear_blocks()), "attenuation flag is 0");
}

// The surface's range against the candidates of a piecewise bilinear
// function's extremes, found independently: every grid point inside the
// rectangle, its corners, and where its sides cross grid lines.
TEST(Surface, RangeIsExactOverAnyRectangle) {
  std::mt19937 rng(5);
  for (int round = 0; round < 20; ++round) {
    const int nx = 2 + rng() % 40, ny = 2 + rng() % 40;
    const double dx = 10 + rng() % 50, dy = 10 + rng() % 50, x0 = -100, y0 = 50;
    std::vector<float> z(size_t(nx) * ny);
    for (float& v : z) v = float(rng() % 2000) - 500;
    auto s = Surface::from_grid(nx, ny, x0, y0, dx, dy, z);
    std::uniform_real_distribution<double> ux(x0 - 200, x0 + nx * dx + 100),
        uy(y0 - 200, y0 + ny * dy + 100);
    for (int n = 0; n < 200; ++n) {
      double a = ux(rng), b = ux(rng), c = uy(rng), d = uy(rng);
      if (a > b) std::swap(a, b);
      if (c > d) std::swap(c, d);
      double lo = HUGE_VAL, hi = -HUGE_VAL;
      auto take = [&](double x, double y) {
        const double e = s->elevation(x, y);
        lo = std::min(lo, e), hi = std::max(hi, e);
      };
      for (double x : {a, b})
        for (double y : {c, d}) take(x, y);
      for (int i = 0; i < nx; ++i) {
        const double x = x0 + i * dx;
        if (x < a || x > b) continue;
        take(x, c), take(x, d);
        for (int j = 0; j < ny; ++j) {
          const double y = y0 + j * dy;
          if (y >= c && y <= d) take(x, y);
        }
      }
      for (int j = 0; j < ny; ++j) {
        const double y = y0 + j * dy;
        if (y >= c && y <= d) take(a, y), take(b, y);
      }
      double got_lo, got_hi;
      s->range(a, b, c, d, &got_lo, &got_hi);
      ASSERT_NEAR(got_lo, lo, 1e-6) << round << " " << n;
      ASSERT_NEAR(got_hi, hi, 1e-6) << round << " " << n;
    }
  }
}

TEST(Surface, AscRasterTakesKeywordsInAnyCaseAndRowsFromTheNorth) {
  testing::TempDir dir;
  // 4 columns (east) x 3 rows (north), cell centres at 50 + 100 c east and
  // 50 + 100 r north; elevation 10 c + r (r counted from the south).
  std::string text = "NCOLS 4\nnRows 3\nXLLCORNER 0\nyllcorner 0\nCellSize 100\n";
  for (int r = 2; r >= 0; --r) {
    for (int c = 0; c < 4; ++c) text += std::to_string(10 * c + r) + " ";
    text += "\n";
  }
  const std::string path = dir.file("g.asc");
  write_file(path, text);
  SurfaceSource src;
  ASSERT_OK(parse_surface_source("asc:" + path, &src));
  std::unique_ptr<Surface> s;
  ASSERT_OK(load_surface(src, nullptr, 1 << 20, &s));
  // The mesh's x is north (rows), y east (columns).
  EXPECT_DOUBLE_EQ(s->elevation(50, 50), 0);
  EXPECT_DOUBLE_EQ(s->elevation(250, 50), 2);
  EXPECT_DOUBLE_EQ(s->elevation(50, 350), 30);
  EXPECT_DOUBLE_EQ(s->elevation(150, 200), 16);
  EXPECT_DOUBLE_EQ(s->highest(), 32);
  // dx, dy and xllcenter; NODATA (the default -9999) filled from a neighbour.
  write_file(path, "ncols 2\nnrows 2\nxllcenter 0\nyllcenter 0\ndx 10\ndy 20\n5 -9999\n1 2\n");
  ASSERT_OK(load_surface(src, nullptr, 1 << 20, &s));
  EXPECT_EQ(s->filled, 1u);
  EXPECT_DOUBLE_EQ(s->elevation(0, 0), 1);    // south-west
  EXPECT_DOUBLE_EQ(s->elevation(20, 0), 5);   // north-west
  EXPECT_DOUBLE_EQ(s->elevation(20, 10), 5);  // north-east, filled from its west
  // Bad rasters: one line each.
  for (const char* bad :
       {"ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n",
        "ncols 2\nnrows 2\nxllcorner 0\ncellsize 1\n1 2 3 4\n", "ncols x\nnrows 2\n",
        "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\n"
        "cellsize 0\n1 2 3 4\n",
        "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n"
        "-9999 -9999 -9999 -9999\n"}) {
    write_file(path, bad);
    const Status st = load_surface(src, nullptr, 1 << 20, &s);
    EXPECT_FALSE(st.ok()) << bad;
    EXPECT_EQ(st.message().find('\n'), std::string::npos);
  }
}

}  // namespace
}  // namespace weaver

namespace weaver {
namespace {

// `model import --from rfile:`: every model octant holds the file's value
// at its centre (as RfileModel samples it), no octant is coarser than its
// block's spacing unless its merged siblings agreed, and the box and the
// origin come from the file.
TEST(Rfile, ImportsAsAModelDatabaseOfItsBlocksCells) {
  testing::TempDir dir;
  RfileWriter w;
  const std::string path = dir.file("m.rfile");
  write_file(path, w.bytes(linear_blocks()));
  ModelImportOptions o;
  o.from = "rfile:" + path;
  ModelImportResult r;
  const std::string db = dir.file("model.db");
  ASSERT_OK(import_model(db, o, &r));
  EXPECT_TRUE(r.info.has_q);
  EXPECT_DOUBLE_EQ(r.info.origin_m[2], -200);
  EXPECT_DOUBLE_EQ(r.info.extent_m[0], 300);
  EXPECT_EQ(r.info.geo, "-118.25,34.5,12.5");
  std::unique_ptr<RfileModel> file;
  ASSERT_OK(RfileModel::open(path, MemoryBudget(1 << 20), 1, &file));
  std::unique_ptr<DbModel> model;
  ASSERT_OK(DbModel::open(db, MemoryBudget(4 << 20), 1, &model));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ux(0, 299), uy(0, 179), uz(-199, 1499);
  for (int n = 0; n < 2000; ++n) {
    const double x = ux(rng), y = uy(rng), z = uz(rng);
    ModelHit h;
    ASSERT_OK(model->lookup(x, y, z, &h));
    const double t = r.info.tick_m, e = octant_edge(h.octant) * t;
    const Material want =
        file->at(std::min(h.octant.x * t + e / 2, 300.0), std::min(h.octant.y * t + e / 2, 180.0),
                 std::min(h.octant.z * t + e / 2 - 200, 1500.0));
    // Merged octants hold their children's common value: the one at the
    // centre of the child holding the point is the same.
    ASSERT_NEAR(h.values[1], want.vs, 0.05 * e) << x << " " << y << " " << z;
    // Within a cell's gradient of the file's own value, but where a cell
    // straddles the blocks' boundary (z = 100 m), whose values jump.
    if (std::abs(z - 100) > e) {
      EXPECT_LE(std::abs(h.values[1] - file->at(x, y, z).vs), 0.05 * e + 1e-3) << z;
    }
  }
}

}  // namespace
}  // namespace weaver

namespace weaver {
namespace {

std::string model_table_bytes(const std::string& db) {
  for (const auto& entry : std::filesystem::directory_iterator(db)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("model-", 0) == 0) {
      std::ifstream in(entry.path(), std::ios::binary);
      return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    }
  }
  return "";
}

// The import samples subtrees on threads, each merged on its own thread,
// and passes them on in key order: the table is the serial one, byte for
// byte, with tiny subtrees (so that merges cross them) and merging within
// a tolerance or exactly.
TEST(Rfile, ImportOnThreadsWritesTheSerialTable) {
  testing::TempDir dir;
  RfileWriter w;
  const std::string path = dir.file("m.rfile");
  write_file(path, w.bytes(linear_blocks()));
  for (const double tolerance : {0.0, 0.02}) {
    std::string serial;
    for (const int threads : {1, 2, 3}) {
      ModelImportOptions o;
      o.from = "rfile:" + path;
      o.tolerance = tolerance;
      o.threads = threads;
      o.rfile_task_cells = 7;
      ModelImportResult r;
      const std::string db =
          dir.file("t" + std::to_string(threads) + "-" + std::to_string(tolerance));
      ASSERT_OK(import_model(db, o, &r));
      const std::string bytes = model_table_bytes(db);
      ASSERT_FALSE(bytes.empty());
      if (threads == 1) {
        serial = bytes;
        if (tolerance > 0) {
          EXPECT_LT(r.octants, r.read / 2);  // merges happened
        }
      } else {
        EXPECT_TRUE(bytes == serial) << threads << " threads, tolerance " << tolerance;
      }
    }
  }
}

}  // namespace
}  // namespace weaver
