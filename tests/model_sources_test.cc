// Model import from the text sources users publish: 1-D layer tables and
// xyz grids (ASCII, any order).  Each is checked against the plain reading of
// its file; bad files are refused naming the line, leaving no table.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "bench_util.h"
#include "db/database.h"
#include "model/grid_model.h"
#include "model/layer_table.h"
#include "modeldb/db_model.h"
#include "modeldb/model_import.h"
#include "storage/btree.h"
#include "test_util.h"

namespace weaver {
namespace {

std::string fresh_db(const std::string& name) {
  return testing::fresh_path("model_sources_" + name);
}

std::string write_text(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "model_sources_" + name;
  std::ofstream(path) << text;
  return path;
}

Status import_from(const std::string& db, const std::string& from) {
  ModelImportOptions o;
  o.from = from;
  o.memory = MemoryBudget(8ull << 20);
  ModelImportResult r;
  return import_model(db, o, &r);
}

bool has_model_table(const std::string& db) {
  std::unique_ptr<Database> d;
  return Database::open(db, Database::Mode::kRead, false, &d).ok() && d->has_table(kModelTable);
}

// Southern California's 1-D model (Hadley and Kanamori, 1977, as SCEC
// publishes it), with Q; and an awkward one whose tops share no round divisor.
const char* kHadleyKanamori =
    "# top  vp   vs   rho  qp  qs\n"
    "0      5500 3180 2400 600 300\n"
    "5500   6300 3640 2670 700 350   # upper crust\n"
    "\n"
    "16000  6700 3870 2800 800 400\n"
    "32000  7800 4500 3000 900 450\n";
const char* kAwkward =
    "0 1800 300 1900\n"
    "12.345 2500 900 2000\n"
    "400.5 4000 2300 2400\n"
    "7777.777 6000 3500 2700\n";

// The slow reference: the last layer whose top is at or above z.
const Layer& layer_at(const LayerTable& t, double z) {
  size_t i = 0;
  while (i + 1 < t.layers.size() && t.layers[i + 1].top_m <= z) ++i;
  return t.layers[i];
}

TEST(ModelSources, LayersAnswerTheLayerAtEachDepthAnywhereAcross) {
  for (const char* text : {kHadleyKanamori, kAwkward}) {
    const std::string file = write_text("layers.txt", text);
    LayerTable table;
    ASSERT_TRUE(read_layer_table(file, &table).ok());
    const std::string db = fresh_db("layers");
    const Status st = import_from(db, "layers:" + file);
    ASSERT_TRUE(st.ok()) << st.to_string();
    std::unique_ptr<DbModel> m;
    ASSERT_TRUE(DbModel::open(db, MemoryBudget(), 1, &m).ok());
    EXPECT_EQ(m->info().has_q, table.has_q);
    std::mt19937_64 rng(7);
    const double deepest = table.layers.back().top_m;
    std::vector<double> depths;
    for (const Layer& l : table.layers) {
      // Each top, and just above it: exact tops hold to 1 mm, rounded ones
      // to half a tick.
      const double near =
          m->info().producer.find("exact") != std::string::npos ? 0.001 : m->info().tick_m;
      if (near < m->info().tick_m) depths.push_back(l.top_m);
      depths.push_back(l.top_m + near);
      if (l.top_m > 0) depths.push_back(l.top_m - near);
    }
    for (int i = 0; i < 3000; ++i)
      depths.push_back(std::uniform_real_distribution<>(0, 2 * deepest)(rng));
    for (double z : depths) {
      const double x = std::uniform_real_distribution<>(-1e6, 1e6)(rng);
      const double y = std::uniform_real_distribution<>(-1e6, 1e6)(rng);
      ModelHit h;
      ASSERT_TRUE(m->lookup(x, y, z, &h).ok());
      const Layer& want = layer_at(table, z);
      EXPECT_FALSE(h.clamped && z < deepest) << z;
      for (int f = 0; f < (table.has_q ? 5 : 3); ++f) {
        ASSERT_EQ(h.values[f], want.values[f]) << "depth " << z << " field " << f;
      }
    }
  }
}

// weaver query MODEL.db material answers from a model database as weaver
// model material does; other queries are refused in one line.
TEST(ModelSources, QueryAnswersMaterialFromAModelDatabase) {
  const std::string file = write_text("query_layers.txt", kHadleyKanamori);
  const std::string db = fresh_db("query_layers");
  ASSERT_TRUE(import_from(db, "layers:" + file).ok());
  uint64_t rss = 0;
  const std::string q =
      bench::run_program({WEAVER_BINARY, "query", db, "material", "100", "-200", "6000"}, &rss);
  EXPECT_EQ(q, "100 -200 6000 6300 3640 2670 700 350\n");
  const std::string m =
      bench::run_program({WEAVER_BINARY, "model", "material", db, "100", "-200", "6000"}, &rss);
  EXPECT_EQ(q, m);
  const std::string cmd =
      std::string(WEAVER_BINARY) + " query " + db + " locate 1 2 3 >/dev/null 2>&1";
  EXPECT_EQ(WEXITSTATUS(std::system(cmd.c_str())), 2);
  // The shell answers from the model table too, line by line.
  const std::string lines = write_text("query_shell.txt",
                                       "material 100 -200 6000\n# a comment\n"
                                       "material 0 0 40000\n.quit\nmaterial 1 1 1\n");
  const std::string shell =
      std::string(WEAVER_BINARY) + " shell " + db + " <" + lines + " >" + db + ".shell 2>&1";
  EXPECT_EQ(WEXITSTATUS(std::system(shell.c_str())), 0);
  const std::string out = testing::slurp(db + ".shell");
  EXPECT_EQ(out, q + "0 0 40000 7800 4500 3000 900 450\n");
}

TEST(ModelSources, BadLayerTablesAreRefusedNamingTheLine) {
  const std::pair<const char*, const char*> cases[] = {
      {"0 5500 3180 2400\n16000 6700 3870 2800\n5500 6300 3640 2670\n", ":3: tops must increase"},
      {"100 5500 3180 2400\n", ":1: the first layer's top must be 0"},
      {"0 5500 -3180 2400\n", ":1: Vs"},
      {"0 5500 3180 2400\n10 1 2\n", ":2: a layer is"},
      {"0 5500 3180 2400 600 300\n10 5500 3180 2400\n", ":2: give Qp and Qs"},
      {"0 5500 3180 2400\n10 fast 3180 2400\n", ":2: 'fast' is not a number"},
      {"0 5500 nan 2400\n", ":1: Vs"},
      {"# nothing\n", ": no layers"},
  };
  for (const auto& [text, error] : cases) {
    const std::string file = write_text("bad_layers.txt", text);
    const std::string db = fresh_db("bad_layers");
    const Status st = import_from(db, "layers:" + file);
    ASSERT_FALSE(st.ok()) << text;
    EXPECT_NE(st.message().find(file + error), std::string::npos) << st.message();
    EXPECT_FALSE(has_model_table(db));
  }
}

struct XyzCase {
  GridSpec g;
  std::vector<Material> values;
};

XyzCase make_grid() {
  XyzCase c;
  c.g.nx = 23, c.g.ny = 17, c.g.nz = 9;
  c.g.x0 = -1200, c.g.y0 = 350.5, c.g.z0 = 0;
  c.g.dx = c.g.dy = c.g.dz = 250;
  for (int k = 0; k < c.g.nz; ++k)
    for (int j = 0; j < c.g.ny; ++j)
      for (int i = 0; i < c.g.nx; ++i) {
        const float vs = 400 + 11 * i + 5 * j + 90 * k + ((i + 2 * j) % 7 == 0 ? 33 : 0);
        c.values.push_back({1.8f * vs, vs, 1900 + vs / 8});
      }
  return c;
}

// The grid's points as xyz lines, shuffled, with comments and blank lines.
std::string xyz_text(const XyzCase& c, uint64_t seed, size_t drop_line = SIZE_MAX) {
  std::vector<std::string> lines;
  char buf[200];
  for (size_t p = 0; p < c.values.size(); ++p) {
    const size_t i = p % c.g.nx, j = p / c.g.nx % c.g.ny, k = p / c.g.nx / c.g.ny;
    std::snprintf(buf, sizeof buf, "%.10g %.10g %.10g %.9g %.9g %.9g\n", c.g.x0 + i * c.g.dx,
                  c.g.y0 + j * c.g.dy, c.g.z0 + k * c.g.dz, c.values[p].vp, c.values[p].vs,
                  c.values[p].rho);
    lines.push_back(buf);
  }
  if (drop_line < lines.size()) lines[drop_line] = lines[(drop_line + 1) % lines.size()];
  std::mt19937_64 rng(seed);
  std::shuffle(lines.begin(), lines.end(), rng);
  std::string text = "# x y z vp vs rho\n\n";
  for (const std::string& l : lines) text += l;
  return text;
}

// Every record of a model table, key and payload.
std::vector<std::pair<uint64_t, std::string>> table_records(const std::string& db) {
  std::unique_ptr<Database> d;
  EXPECT_TRUE(Database::open(db, Database::Mode::kRead, false, &d).ok());
  std::unique_ptr<BTree> t;
  EXPECT_TRUE(d->open_table(kModelTable, 4 << 20, &t).ok());
  std::vector<std::pair<uint64_t, std::string>> out;
  std::unique_ptr<Cursor> c;
  EXPECT_TRUE(t->seek(0, &c).ok());
  for (; c->valid(); (void)c->next()) {
    out.emplace_back(c->key(), std::string(reinterpret_cast<const char*>(c->payload()), 12));
  }
  return out;
}

TEST(ModelSources, XyzInAnyOrderImportsAsItsGridDoes) {
  const XyzCase c = make_grid();
  const std::string grid = ::testing::TempDir() + "model_sources.grid";
  ASSERT_TRUE(write_grid_model(grid, c.g, c.values).ok());
  const std::string from_grid = fresh_db("xyz_as_grid");
  ASSERT_TRUE(import_from(from_grid, "grid:" + grid).ok());
  const auto want = table_records(from_grid);
  ASSERT_EQ(want.size(), c.values.size());
  for (uint64_t seed : {1, 2}) {
    const std::string file = write_text("grid.xyz", xyz_text(c, seed));
    const std::string db = fresh_db("xyz");
    const Status st = import_from(db, "xyz:" + file);
    ASSERT_TRUE(st.ok()) << st.to_string();
    EXPECT_EQ(table_records(db), want);
    EXPECT_FALSE(std::filesystem::exists(db + "/xyz-import.grid.tmp"));
  }
}

TEST(ModelSources, BadXyzFilesAreRefusedNamingWhatIsWrong) {
  const XyzCase c = make_grid();
  std::string uneven = xyz_text(c, 3);
  uneven += "-1200 350.5 3000 1000 500 2000\n";  // z 3000: off the 250 m steps
  const std::pair<std::string, std::string> cases[] = {
      {xyz_text(c, 3, 100), "no line gives grid point (800, 1350.5, 0)"},
      {xyz_text(c, 3) + "0 0\n", ":3522: a point is 'x y z vp vs rho', not 2 numbers"},
      {"0 0 0 1 1 1\n0 0 1 1 1 1\n", "at least 2 distinct x values"},
      {uneven, "z values are not evenly spaced"},
      {"0 0 0 1000 -5 2000\n", ":1: Vs"},
      {"0 0 0 1000 5 2000 7\n", ":1: more than 6 numbers"},
      {"0 0 zero 1000 5 2000\n", ":1: 'zero' is not a number"},
      {"0 0 0 1 1 1\n1 0 0 1 1 1\n0 1 0 1 1 1\n1 1 0 1 1 1\n0 0 1 1 1 1\n1 1 1 1 1 1\n",
       "6 points for a 2 x 2 x 2 grid (8)"},
  };
  for (const auto& [text, error] : cases) {
    const std::string file = write_text("bad.xyz", text);
    const std::string db = fresh_db("bad_xyz");
    const Status st = import_from(db, "xyz:" + file);
    ASSERT_FALSE(st.ok()) << error;
    EXPECT_NE(st.message().find(error), std::string::npos) << st.message();
    EXPECT_EQ(st.message().rfind(file, 0), 0u) << st.message();
    EXPECT_FALSE(has_model_table(db));
    EXPECT_FALSE(std::filesystem::exists(db + "/xyz-import.grid.tmp"));
  }
}

// construct --model etree:FILE (and layers:FILE) imports the model into the
// database it builds, and its leaves take their values from there, those
// balance adds too (mesh runs both); a bad model file fails the command in
// one line, leaving no table.
TEST(ModelSources, ConstructImportsAModelFileIntoItsDatabase) {
  const std::string etree = std::string(WEAVER_SOURCE_DIR) + "/tests/data/etree/cmu.e";
  const std::string layers = write_text("construct_layers.txt", kHadleyKanamori);
  for (const std::string& from : {"etree:" + etree, "layers:" + layers}) {
    const std::string db = fresh_db("construct_from_file");
    uint64_t rss = 0;
    const std::string out =
        bench::run_program({WEAVER_BINARY, "mesh", db, "--model", from, "--freq", "0.1", "--domain",
                            "40000,40000,20000", "--threads", "2", "--quiet"},
                           &rss);
    ASSERT_NE(out.find("balanced   "), std::string::npos) << out;
    ASSERT_NE(out.find("imported   " + from), std::string::npos) << out;
    ASSERT_NE(out.find("elements per level"), std::string::npos) << out;
    std::unique_ptr<DbModel> m;
    ASSERT_TRUE(DbModel::open(db, MemoryBudget(), 1, &m).ok());
    std::unique_ptr<Database> d;
    ASSERT_TRUE(Database::open(db, Database::Mode::kRead, false, &d).ok());
    std::unique_ptr<BTree> t;
    ASSERT_TRUE(d->open_table("octants", 4 << 20, &t).ok());
    const double tick = 40000.0 / kRootEdge;  // one block of 40 km
    // The layer table has Qp and Qs, cmu.e has not: the leaves carry them
    // exactly when the model does.
    const int fields = from[0] == 'l' ? 5 : 3;
    ASSERT_EQ(t->options().schema.record_size(), 4u * fields) << from;
    ASSERT_EQ(m->has_q(), fields == 5) << from;
    std::unique_ptr<Cursor> c;
    ASSERT_TRUE(t->seek(0, &c).ok());
    uint64_t leaves = 0;
    for (; c->valid(); (void)c->next(), ++leaves) {
      const Octant o = octant_from_key(c->key());
      float leaf[5];
      std::memcpy(leaf, c->payload(), 4 * fields);
      const double half = octant_edge(o) / 2.0;
      ModelHit h;
      ASSERT_TRUE(
          m->lookup((o.x + half) * tick, (o.y + half) * tick, (o.z + half) * tick, &h).ok());
      for (int f = 0; f < fields; ++f) ASSERT_EQ(leaf[f], h.values[f]) << from << " field " << f;
    }
    EXPECT_GT(leaves, 8u) << from;
  }
  const std::string bad = write_text("construct_bad_layers.txt", "0 1 1 1\n5 1 -1 1\n");
  const std::string db = fresh_db("construct_bad");
  const std::string cmd = std::string(WEAVER_BINARY) + " construct " + db +
                          " --model layers:" + bad + " --freq 0.1 --quiet 2>" + db + ".err";
  EXPECT_EQ(WEXITSTATUS(std::system(cmd.c_str())), 1);
  std::ifstream err(db + ".err");
  std::string line, more;
  std::getline(err, line);
  EXPECT_NE(line.find(bad + ":2: Vs"), std::string::npos) << line;
  EXPECT_FALSE(std::getline(err, more)) << more;
  EXPECT_FALSE(has_model_table(db));
}

// A batch answers in Z-order, whatever the points' order: each point gets
// what it alone would get, outside the model's box too (clamped, and said).
TEST(ModelSources, BatchLookupsAnswerAsSingleOnesInAnyOrder) {
  const std::string etree = std::string(WEAVER_SOURCE_DIR) + "/tests/data/etree/cmu.e";
  const std::string db = fresh_db("batch");
  ASSERT_TRUE(import_from(db, "etree:" + etree).ok());
  std::unique_ptr<DbModel> m;
  ASSERT_TRUE(DbModel::open(db, MemoryBudget(), 1, &m).ok());
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> coord(-20000, 120000);  // the box is 0..100 km
  std::vector<double> xyz(3 * 20000);
  for (double& v : xyz) v = coord(rng);
  std::vector<ModelHit> hits(xyz.size() / 3);
  ASSERT_TRUE(m->lookup_batch(xyz.data(), hits.size(), hits.data()).ok());
  size_t clamped = 0;
  for (size_t i = 0; i < hits.size(); ++i) {
    ModelHit one;
    ASSERT_TRUE(m->lookup(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2], &one).ok());
    ASSERT_EQ(hits[i].values, one.values) << i;
    ASSERT_EQ(hits[i].octant, one.octant) << i;
    ASSERT_EQ(hits[i].clamped, one.clamped) << i;
    bool inside = true;
    for (int a = 0; a < 3; ++a) inside = inside && xyz[3 * i + a] >= 0 && xyz[3 * i + a] < 1e5;
    ASSERT_EQ(hits[i].clamped, !inside) << i;
    clamped += !inside;
  }
  EXPECT_GT(clamped, 1000u);
}

// --outside: points and domains past the model's box take its nearest cell
// (the default, said once) or are refused in one line, naming them.
TEST(ModelSources, OutsideTheModelIsClampedAndSaidOrRefused) {
  const std::string etree = std::string(WEAVER_SOURCE_DIR) + "/tests/data/etree/cmu.e";
  const std::string db = fresh_db("outside");
  ASSERT_TRUE(import_from(db, "etree:" + etree).ok());
  const std::string points = write_text("outside_points.txt", "10 10 10\n150000 5 5\n-1 2 3\n");
  const std::string base = std::string(WEAVER_BINARY) + " model material " + db + " --points " +
                           points + " >" + db + ".out 2>" + db + ".err";
  ASSERT_EQ(WEXITSTATUS(std::system(base.c_str())), 0);
  const std::string answers = testing::slurp(db + ".out");
  EXPECT_EQ(std::count(answers.begin(), answers.end(), '\n'), 3) << answers;
  const std::string note = testing::slurp(db + ".err");
  EXPECT_NE(note.find("2 point(s) outside the model's box"), std::string::npos) << note;
  EXPECT_NE(note.find("first: (150000, 5, 5) m"), std::string::npos) << note;
  ASSERT_EQ(WEXITSTATUS(std::system((base + " --outside error").c_str())), 1);
  const std::string err = testing::slurp(db + ".err");
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("point (150000, 5, 5) m is outside the model's box (x 0..100000"),
            std::string::npos)
      << err;
  // construct over a domain twice the model's width.
  const std::string mesh = fresh_db("outside_mesh");
  const std::string construct =
      std::string(WEAVER_BINARY) + " construct " + mesh + " --model db:" + db +
      " --freq 0.05 --domain 200000,100000,50000 --quiet >" + mesh + ".out 2>" + mesh + ".err";
  ASSERT_EQ(WEXITSTATUS(std::system((construct + " --outside error").c_str())), 1);
  const std::string refused = testing::slurp(mesh + ".err");
  EXPECT_NE(refused.find("x past 100000 m (to 200000)"), std::string::npos) << refused;
  EXPECT_EQ(std::count(refused.begin(), refused.end(), '\n'), 1) << refused;
  EXPECT_FALSE(std::filesystem::exists(mesh + "/octants-1.bt"));
  ASSERT_EQ(WEXITSTATUS(std::system(construct.c_str())), 0);
  const std::string plan = testing::slurp(mesh + ".out");
  EXPECT_NE(plan.find("outside    the domain reaches outside the model's box: x past 100000 m"),
            std::string::npos)
      << plan;
}

// A mesh whose model has Q answers point queries with qp and qs, in text
// and in the column formats, single points and batches.
TEST(ModelSources, QueriesOnAMeshWithQGiveQpAndQs) {
  const std::string table = write_text("q_layers.txt", kHadleyKanamori);
  const std::string db = fresh_db("q_mesh");
  uint64_t rss = 0;
  ASSERT_NE(bench::run_program({WEAVER_BINARY, "mesh", db, "--model", "layers:" + table, "--freq",
                                "0.1", "--domain", "64000,64000,48000", "--quiet"},
                               &rss),
            "");
  const std::string text = bench::run_program(
      {WEAVER_BINARY, "query", db, "material", "100", "200", "6000", "--units", "m"}, &rss);
  EXPECT_NE(text.find("vp 6300 m/s, vs 3640 m/s, rho 2670 kg/m^3, qp 700, qs 350"),
            std::string::npos)
      << text;
  // The third point lies past the domain: its row is empty after its
  // status, as many fields as the header names (qp and qs included).
  const std::string points = write_text("q_points.txt", "100 200 6000\n5 5 40000\n5 5 90000\n");
  const std::string csv = bench::run_program({WEAVER_BINARY, "query", db, "material", "--points",
                                              points, "--units", "m", "--format", "csv"},
                                             &rss);
  EXPECT_NE(csv.find("x,y,z,status,element,vp,vs,rho,qp,qs\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",6300,3640,2670,700,350\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",7800,4500,3000,900,450\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find("5,5,90000,outside,,,,,,\n"), std::string::npos) << csv;
  for (const char* mode : {"json", "text"}) {
    const std::string rows = bench::run_program({WEAVER_BINARY, "query", db, "locate", "--points",
                                                 points, "--units", "m", "--format", mode},
                                                &rss);
    const std::string outside =
        std::string(mode) == "json"
            ? "\"status\": \"outside\", \"element\": null, \"level\": null, "
              "\"edge\": null, \"corner_x\": null, \"corner_y\": null, "
              "\"corner_z\": null, \"vp\": null, \"vs\": null, \"rho\": "
              "null, \"qp\": null, \"qs\": null}"
            : "5 5 90000 outside - - - - - - - - - - -\n";
    EXPECT_NE(rows.find(outside), std::string::npos) << rows;
  }
  const std::string element =
      bench::run_program({WEAVER_BINARY, "query", db, "element", "0", "--format", "csv"}, &rss);
  EXPECT_NE(element.find(",vp,vs,rho,qp,qs\n"), std::string::npos) << element;
  EXPECT_NE(element.find(",5500,3180,2400,600,300\n"), std::string::npos) << element;
}

}  // namespace
}  // namespace weaver
