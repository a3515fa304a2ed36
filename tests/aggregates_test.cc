// The aggregate table (query/aggregates.h) against a summary made the
// obvious way: every leaf added to each of its ancestors in a map.  On
// generated octrees (non-cube domains, holes as fine as the leaves, deep
// grading) and on the basin's material; spooled out of core or not; read
// back by Explorer's aggregate hits and by the map tiles; dropped with the
// octants; and checked by verify.
#include "query/aggregates.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <random>

#include "cli_run.h"
#include "construct/construct.h"
#include "db/database.h"
#include "mesh/mesh_reader.h"
#include "query/explorer.h"
#include "sample_octrees.h"
#include "serve/tiles.h"
#include "storage/btree.h"
#include "test_octrees.h"
#include "test_util.h"
#include "verify/verify.h"

namespace weaver {
namespace {

struct Expected {
  uint64_t leaves = 0;
  int level_min = kMaxLevel, level_max = 0;
  std::array<float, 5> min{}, max{};
  std::array<double, 5> sum{};
  double volume = 0;
};

// Every leaf of db's octant table with its fields, added to each ancestor.
std::map<uint64_t, Expected> reference(const std::string& db, int* fields) {
  std::unique_ptr<Mesh> mesh;
  EXPECT_OK(Mesh::open(db, 1 << 20, 1 << 20, &mesh, true));
  *fields = mesh->has_q() ? 5 : mesh->has_material() ? 3 : 0;
  std::map<uint64_t, Expected> out;
  MeshElement e;
  for (uint64_t id = 0; id < mesh->element_count(); ++id) {
    EXPECT_OK(mesh->element(id, false, &e));
    const float v[5] = {e.vp, e.vs, e.rho, e.qp, e.qs};
    const double volume = std::ldexp(1.0, 3 * (kMaxLevel - e.octant.level));
    for (int l = 0; l < e.octant.level; ++l) {
      Expected& x = out[octant_key(octant_ancestor(e.octant, l))];
      if (x.leaves == 0) x.min.fill(INFINITY), x.max.fill(-INFINITY);
      ++x.leaves;
      x.level_min = std::min<int>(x.level_min, e.octant.level);
      x.level_max = std::max<int>(x.level_max, e.octant.level);
      for (int f = 0; f < *fields; ++f) {
        x.min[f] = std::min(x.min[f], v[f]), x.max[f] = std::max(x.max[f], v[f]);
        x.sum[f] += v[f] * volume;
      }
      x.volume += volume;
    }
  }
  return out;
}

void expect_same(const Aggregate& a, const Expected& x, int fields, uint64_t key) {
  const std::string where = describe_octant(octant_from_key(key));
  ASSERT_EQ(a.leaves, x.leaves) << where;
  ASSERT_EQ(a.level_min, x.level_min) << where;
  ASSERT_EQ(a.level_max, x.level_max) << where;
  for (int f = 0; f < fields; ++f) {
    ASSERT_EQ(a.min[f], x.min[f]) << where << " " << kAggregateFields[f];
    ASSERT_EQ(a.max[f], x.max[f]) << where << " " << kAggregateFields[f];
    // The table adds the children's sums, the reference the leaves': the
    // same up to rounding.
    const double mean = x.sum[f] / x.volume;
    ASSERT_NEAR(a.mean[f], mean, 1e-5 * std::abs(mean)) << where << " " << kAggregateFields[f];
  }
}

// The table of db holds exactly the octants with leaves strictly inside,
// each summarised as the reference says.
void expect_table_matches_reference(const std::string& db) {
  int fields = 0;
  const std::map<uint64_t, Expected> want = reference(db, &fields);
  std::unique_ptr<Database> d;
  std::unique_ptr<BTree> t;
  ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &d));
  ASSERT_OK(d->open_table(kAggregateTable, 1 << 20, &t));
  AggregateLayout layout(false, false);
  ASSERT_OK(AggregateLayout::of_table(*t, &layout));
  ASSERT_EQ(layout.fields(), fields);
  ASSERT_EQ(t->size(), want.size());
  int finest = -1;
  BTreeCursor c;
  ASSERT_OK(t->seek_cursor(0, &c));
  for (const auto& [key, x] : want) {
    ASSERT_TRUE(c.valid());
    ASSERT_EQ(c.key(), key);
    Aggregate a;
    layout.decode(c.payload(), &a);
    expect_same(a, x, fields, key);
    if (::testing::Test::HasFatalFailure()) return;
    finest = std::max<int>(finest, octant_from_key(key).level);
    ASSERT_OK(c.next());
  }
  EXPECT_EQ(aggregate_finest(*t), finest);
}

// n points anywhere in the root.
std::vector<Coord> random_points(uint64_t seed, size_t n) {
  std::mt19937_64 rng(seed);
  std::vector<Coord> pts(n);
  for (Coord& p : pts) {
    p = {uint32_t(rng() % kRootEdge), uint32_t(rng() % kRootEdge), uint32_t(rng() % kRootEdge)};
  }
  return pts;
}

// Each hit is the reference's summary of the octant of `level` holding its
// point, found exactly where the reference has one.
void expect_hits_match(const std::vector<Coord>& pts, const std::vector<AggregateHit>& hits,
                       int level, const std::map<uint64_t, Expected>& want, int fields) {
  for (size_t i = 0; i < pts.size(); ++i) {
    const uint64_t key =
        octant_key(octant_ancestor({pts[i].x, pts[i].y, pts[i].z, kMaxLevel}, level));
    const auto it = want.find(key);
    ASSERT_EQ(hits[i].found, it != want.end()) << describe_octant(octant_from_key(key));
    if (hits[i].found) expect_same(hits[i].a, it->second, fields, key);
    if (::testing::Test::HasFatalFailure()) return;
  }
}

std::string aggregate_file_bytes(const std::string& db) {
  std::unique_ptr<Database> d;
  EXPECT_OK(Database::open(db, Database::Mode::kRead, false, &d));
  std::ifstream in(d->table_path(kAggregateTable), std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

Status build(const std::string& db, uint64_t memory, uint64_t max_records = 0) {
  AggregateOptions o;
  o.memory = MemoryBudget(memory);
  o.max_records = max_records;
  AggregateReport r;
  return build_aggregates(db, o, &r);
}

TEST(Aggregates, MatchTheReferenceOnGeneratedOctrees) {
  testing::TempDir dir;
  const int cases = int(testing::scaled(24, 6));
  for (int i = 0; i < cases; ++i) {
    SCOPED_TRACE("case " + std::to_string(i));
    std::string db;
    if (i % 3 == 0) {
      // 3 x 2 x 1 blocks (not a cube), a stretch cut out when odd.
      db = testing::random_octree(dir, "c" + std::to_string(i), 100 + i, 6 + i % 4, i % 2,
                                  testing::scaled(3000, 800));
    } else if (i % 3 == 1) {
      // Holes as fine as the leaves: octants partly outside the domain.
      db = testing::imported_octree(dir, "c" + std::to_string(i),
                                    testing::random_holed(200 + i, 2000, 7 + i % 3, 0.6));
    } else {
      // Deep grading: 2:1 balanced refinement down to level 12.
      db = testing::imported_octree(
          dir, "c" + std::to_string(i),
          testing::random_balanced(300 + i, 2, 1, 3, 3, testing::scaled(400, 100), 12));
    }
    // The smallest budget spills every level past a few records.
    ASSERT_OK(build(db, i % 2 ? MemoryBudget::kMinBytes : 64 << 20));
    expect_table_matches_reference(db);
    if (HasFatalFailure()) return;
    const std::string spilled = aggregate_file_bytes(db);
    ASSERT_OK(build(db, i % 2 ? 64 << 20 : MemoryBudget::kMinBytes));
    EXPECT_EQ(aggregate_file_bytes(db), spilled) << "the budget changed the table";
  }
}

// The basin built from its model: vp, vs and rho summarised.
std::string basin(const testing::TempDir& dir, double freq = 0.1) {
  ConstructOptions co;
  co.model = "basin";
  co.freq = freq;
  ConstructPlan plan;
  ConstructResult cr;
  EXPECT_OK(construct_octree(dir.file("basin"), co, &plan, &cr));
  return dir.file("basin");
}

TEST(Aggregates, MatchTheReferenceOnTheBasinsMaterial) {
  testing::TempDir dir;
  const std::string db = basin(dir);
  ASSERT_OK(build(db, MemoryBudget::kMinBytes));
  expect_table_matches_reference(db);
}

// Tiles of a z plane at zooms 0 to 5: a pixel whose element is smaller
// than the pixel shows the least vs of the octant of the pixel's size
// around its centre; any other pixel, its element's vs.  Whether the
// octant's summary comes from the table or, for levels finer than the
// table holds, from the leaves.
void expect_tiles_show_least_vs(Explorer& ex, const std::map<uint64_t, Expected>& want) {
  serve::Section s;
  ASSERT_OK(serve::section_of(ex, 2, 1000, &s));
  serve::Paint least;
  ASSERT_OK(serve::paint_of(ex, "vs", "", &least));
  ASSERT_EQ(least.summary, serve::Paint::Summary::kMin);
  uint64_t summarised = 0;
  for (int zoom = 0; zoom <= 5; ++zoom) {
    const int64_t tx = zoom == 0 ? 0 : 1, ty = zoom == 0 ? 0 : 1;
    std::vector<serve::TilePixel> pixels;
    ASSERT_OK(serve::tile_pixels(ex, s, least, zoom, tx, ty, &pixels));
    const double span = s.side / std::ldexp(1.0, zoom), step = span / serve::kTile;
    int level = 0;
    while (octant_edge(level) > step) ++level;
    std::vector<Coord> centres;
    for (int j = 0; j < serve::kTile; ++j) {
      for (int i = 0; i < serve::kTile; ++i) {
        const double u = tx * span + (i + 0.5) * step, v = s.side - ty * span - (j + 0.5) * step;
        centres.push_back({uint32_t(u), uint32_t(v), s.at});
      }
    }
    std::vector<PointHit> hits(centres.size());
    ASSERT_OK(ex.locate_batch(centres.data(), centres.size(), hits.data()));
    for (size_t k = 0; k < centres.size(); ++k) {
      const PointHit& h = hits[k];
      ASSERT_EQ(pixels[k].inside, h.inside);
      if (!h.inside) continue;
      double expect = h.vs;
      if (h.leaf.level > level) {
        expect = want.at(octant_key(octant_ancestor(h.leaf, level))).min[1];
        ++summarised;
      }
      ASSERT_EQ(pixels[k].value, expect) << "zoom " << zoom << " pixel " << k;
    }
  }
  EXPECT_GT(summarised, 200u);  // the check saw summarised pixels
}

TEST(Aggregates, AggregateHitsAndTilesShowTheOctantAroundEachPixel) {
  testing::TempDir dir;
  // Fine enough that zoom 0's pixels hold many elements.
  const std::string db = basin(dir, 0.25);
  ASSERT_OK(build(db, 64 << 20));
  int fields = 0;
  const std::map<uint64_t, Expected> want = reference(db, &fields);
  std::unique_ptr<Explorer> ex;
  ASSERT_OK(Explorer::open(db, MemoryBudget(64 << 20), &ex));
  ASSERT_GE(ex->aggregate_finest(), 3);

  // Aggregate hits: random points at every level of the table.
  const std::vector<Coord> pts = random_points(5, 2000);
  for (int level = 0; level <= ex->aggregate_finest(); ++level) {
    std::vector<AggregateHit> hits(pts.size());
    ASSERT_OK(ex->aggregate_batch(pts.data(), pts.size(), level, hits.data()));
    expect_hits_match(pts, hits, level, want, fields);
    if (HasFatalFailure()) return;
  }
  std::vector<AggregateHit> none(1);
  EXPECT_FALSE(ex->aggregate_batch(pts.data(), 1, ex->aggregate_finest() + 1, none.data()).ok());

  expect_tiles_show_least_vs(*ex, want);
}

// A table of the coarsest levels only: the finer pixels are summarised
// from the leaves, as the table would have them, up to a budget of leaves.
TEST(Aggregates, SummariesFromTheLeavesMatchTheTable) {
  testing::TempDir dir;
  const std::string db = basin(dir, 0.25);
  ASSERT_OK(build(db, 64 << 20, 100));
  int fields = 0;
  const std::map<uint64_t, Expected> want = reference(db, &fields);
  std::unique_ptr<Explorer> ex;
  ASSERT_OK(Explorer::open(db, MemoryBudget(64 << 20), &ex));
  ASSERT_GE(ex->aggregate_finest(), 0);
  ASSERT_LE(ex->aggregate_finest(), 2);
  const std::vector<Coord> pts = random_points(9, 3000);
  for (int level = 0; level < kMaxLevel; ++level) {
    std::vector<AggregateHit> hits(pts.size());
    ASSERT_OK(ex->summarise_batch(pts.data(), pts.size(), level, UINT64_MAX, hits.data()));
    expect_hits_match(pts, hits, level, want, fields);
    if (HasFatalFailure()) return;
  }
  // A budget of leaves: the octants in key order until it is spent.
  std::vector<AggregateHit> hits(pts.size());
  ASSERT_OK(ex->summarise_batch(pts.data(), pts.size(), 3, 500, hits.data()));
  std::map<uint64_t, bool> found;  // by octant key, in key order
  for (size_t i = 0; i < pts.size(); ++i) {
    found[octant_key(octant_ancestor({pts[i].x, pts[i].y, pts[i].z, kMaxLevel}, 3))] |=
        hits[i].found;
  }
  uint64_t read = 0;
  bool spent = false;
  for (const auto& [key, was] : found) {
    const auto it = want.find(key);
    const uint64_t inside = it == want.end() ? 0 : it->second.leaves;
    if (!spent && inside > 0) {
      EXPECT_TRUE(was) << describe_octant(octant_from_key(key));
    }
    if (spent) {
      EXPECT_FALSE(was) << describe_octant(octant_from_key(key));
    }
    read += inside;
    spent = read >= 500;
  }
  EXPECT_TRUE(spent);
  expect_tiles_show_least_vs(*ex, want);
}

TEST(Aggregates, DroppedWhenTheOctantsAreReplaced) {
  testing::TempDir dir;
  const std::string db = testing::random_octree(dir, "db", 7, 6, false, 1000);
  ASSERT_OK(build(db, 64 << 20));
  {
    std::unique_ptr<Database> d;
    ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &d));
    ASSERT_TRUE(d->has_table(kAggregateTable));
  }
  ImportResult ir;
  ASSERT_OK(import_octants(db, dir.file("db.txt"), ImportOptions{}, &ir));
  std::unique_ptr<Database> d;
  ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &d));
  EXPECT_FALSE(d->has_table(kAggregateTable));
}

// A table whose one record is off by a leaf, committed in place of the
// right one: verify names it.
TEST(Aggregates, VerifyFindsARecordThatDiffersFromItsLeaves) {
  testing::TempDir dir;
  const std::string db = basin(dir);
  ASSERT_OK(build(db, 64 << 20));
  VerifyOptions vo;
  VerifyReport vr;
  ASSERT_OK(verify_database(db, vo, &vr));
  ASSERT_TRUE(vr.ok()) << vr.problems[0];
  {
    std::unique_ptr<Database> d;
    ASSERT_OK(Database::open(db, Database::Mode::kWrite, false, &d));
    std::unique_ptr<BTree> good, bad;
    ASSERT_OK(d->open_table(kAggregateTable, 1 << 20, &good));
    std::string file;
    ASSERT_OK(d->create_table(kAggregateTable, good->options(), 1 << 20, &bad, &file));
    BTreeCursor c;
    ASSERT_OK(good->seek_cursor(0, &c));
    std::vector<std::byte> payload(good->payload_size());
    for (uint64_t n = 0; c.valid(); ++n) {
      std::memcpy(payload.data(), c.payload(), payload.size());
      if (n == good->size() / 2) payload[0] = std::byte(uint8_t(payload[0]) + 1);  // leaves + 1
      ASSERT_OK(bad->append(c.key(), payload.data()));
      ASSERT_OK(c.next());
    }
    ASSERT_OK(bad->commit());
    good.reset();
    ASSERT_OK(d->publish(kAggregateTable, file, bad, Status::Ok()));
  }
  ASSERT_OK(verify_database(db, vo, &vr));
  ASSERT_EQ(vr.problems.size(), 1u);
  EXPECT_NE(vr.problems[0].find("table aggregates: the record of octant"), std::string::npos)
      << vr.problems[0];
}

// The command: its errors are one line and exit 2 (usage) or 1; a
// --max-records keeps fewer levels; a model database has nothing to
// summarise.
TEST(Aggregates, CommandKeepsTheLevelsAskedForAndRefusesBadInput) {
  testing::TempDir dir;
  const std::string db = testing::random_octree(dir, "db", 11, 8, false, 20000);
  for (const std::string& bad :
       std::vector<std::string>{"", db + " --max-records 0", db + " --max-records lots",
                                db + " --levels 3", db + " " + db}) {
    const testing::CommandRun r = testing::run("aggregate " + bad);
    EXPECT_EQ(r.code, 2) << bad;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
  const testing::CommandRun all = testing::run("aggregate " + db + " --quiet");
  ASSERT_EQ(all.code, 0) << all.err;
  std::unique_ptr<Database> d;
  std::unique_ptr<BTree> t;
  ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &d));
  ASSERT_OK(d->open_table(kAggregateTable, 1 << 20, &t));
  const int finest = aggregate_finest(*t), records = int(t->size());
  t.reset(), d.reset();
  const testing::CommandRun fewer = testing::run("aggregate " + db + " --max-records 500 --quiet");
  ASSERT_EQ(fewer.code, 0) << fewer.err;
  ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &d));
  ASSERT_OK(d->open_table(kAggregateTable, 1 << 20, &t));
  EXPECT_LT(aggregate_finest(*t), finest);
  EXPECT_LT(int(t->size()), records);
  EXPECT_LE(t->size(), 500u);
  const std::string model = dir.file("model");
  const std::string fixture = std::string(WEAVER_SOURCE_DIR) + "/tests/data/etree/cmu.e";
  ASSERT_EQ(testing::run("model import " + model + " --from etree:" + fixture).code, 0);
  const testing::CommandRun refused = testing::run("aggregate " + model);
  EXPECT_EQ(refused.code, 1);
  EXPECT_NE(refused.err.find("has no octant table"), std::string::npos) << refused.err;
}

}  // namespace
}  // namespace weaver
