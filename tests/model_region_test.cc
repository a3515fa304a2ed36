// ModelRegion: the model octants around a box, decoded, answer every pixel
// of the box as a linear search of all the model's octants does, on random
// models with holes and deep grading; a region past its octant cap stays
// unloaded.
#include "modeldb/model_region.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "db/database.h"
#include "modeldb/model_table.h"
#include "storage/btree.h"
#include "verify/verify.h"

namespace weaver {
namespace {

struct ModelOctant {
  Octant o;
  ModelValues v;
};

// A random octree: random refinement down to level 5, and down to `depth`
// around a point (deep grading, so a large box's raster is coarser than its
// finest octants), with about one leaf in `hole_one_in` left out.
void grow(const Octant& o, int depth, Coord focus, std::mt19937_64& rng, int hole_one_in,
          std::vector<ModelOctant>* out) {
  const uint32_t e = octant_edge(o);
  const bool near = focus.x - o.x < e && focus.y - o.y < e && focus.z - o.z < e;
  const bool split = o.level < depth && (near || (o.level < 5 && rng() % 3 == 0));
  if (split) {
    for (int k = 0; k < 8; ++k) grow(octant_child(o, k), depth, focus, rng, hole_one_in, out);
    return;
  }
  if (rng() % hole_one_in == 0) return;
  const float vs = 100.0f + float(rng() % 4000);
  out->push_back({o, ModelValues{2 * vs, vs, 2000, 0, 0}});
}

std::string write_model(const std::string& name, const std::vector<ModelOctant>& octants) {
  const std::string dir = ::testing::TempDir() + "model_region_" + name;
  std::filesystem::remove_all(dir);
  std::unique_ptr<Database> db;
  EXPECT_TRUE(Database::open(dir, Database::Mode::kWrite, true, &db).ok());
  TableOptions topt;
  topt.key_kind = KeyKind::kOctant;
  topt.schema = material_schema(false);
  std::unique_ptr<BTree> t;
  std::string file;
  EXPECT_TRUE(db->create_table(kModelTable, topt, 8 << 20, &t, &file).ok());
  std::vector<ModelOctant> sorted = octants;
  std::sort(sorted.begin(), sorted.end(), [](const ModelOctant& a, const ModelOctant& b) {
    return octant_key(a.o) < octant_key(b.o);
  });
  Status st;
  for (const ModelOctant& m : sorted) {
    if (st.ok()) st = t->append(octant_key(m.o), reinterpret_cast<const std::byte*>(m.v.data()));
  }
  EXPECT_TRUE(db->publish(kModelTable, file, t, st).ok());
  return dir;
}

// The slow reference: the octant holding p, by looking at every one.
int reference(const std::vector<ModelOctant>& octants, Coord p) {
  for (size_t i = 0; i < octants.size(); ++i) {
    if (octant_contains_point(octants[i].o, p)) return static_cast<int>(i);
  }
  return -1;
}

TEST(ModelRegion, AnswersEveryPixelAsALinearSearchDoes) {
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    std::mt19937_64 rng(seed);
    const Coord focus{uint32_t(rng() % kRootEdge), uint32_t(rng() % kRootEdge),
                      uint32_t(rng() % kRootEdge)};
    std::vector<ModelOctant> octants;
    grow(octant_root(), 6 + 2 * int(seed % 4), focus, rng, seed % 2 ? 7 : 1000000, &octants);
    const std::string dir = write_model(std::to_string(seed), octants);
    std::unique_ptr<Database> db;
    ASSERT_TRUE(Database::open(dir, Database::Mode::kRead, false, &db).ok());
    std::unique_ptr<BTree> t;
    ASSERT_TRUE(db->open_table(kModelTable, 8 << 20, &t).ok());
    // One region for all the boxes, as a model database's reader keeps
    // one: each load must answer as if the last had never been.
    ModelRegion r;
    for (int box = 0; box < 40; ++box) {
      // Boxes of every size, from a few pixels to the whole root, some
      // unaligned, some around the finely graded point.
      const uint32_t side = 1 + uint32_t(rng() % (kRootEdge >> (rng() % 14)));
      Coord lo;
      uint32_t* c[3] = {&lo.x, &lo.y, &lo.z};
      const uint32_t f[3] = {focus.x, focus.y, focus.z};
      for (int a = 0; a < 3; ++a) {
        const uint32_t centre = box % 2 ? f[a] : uint32_t(rng() % kRootEdge);
        *c[a] = std::min(centre - std::min(centre, side / 2), kRootEdge - side);
      }
      const Coord hi{lo.x + side - 1, lo.y + side - 1, lo.z + side - 1};
      ASSERT_TRUE(r.load(*t, lo, hi, 12, 1u << 20).ok());
      ASSERT_TRUE(r.loaded());
      for (int s = 0; s < 400; ++s) {
        // Corners and edges of the box as often as its inside.
        const auto pick = [&](uint32_t l, uint32_t h) {
          const uint64_t k = rng() % 6;
          return k == 0 ? l : k == 1 ? h : l + uint32_t(rng() % (uint64_t{h} - l + 1));
        };
        // And, in boxes around the graded point, its fine octants often.
        const auto near = [&](uint32_t f, uint32_t l, uint32_t h) {
          const uint32_t v = f - std::min<uint32_t>(f, 4096) + uint32_t(rng() % 8192);
          return std::clamp(v, l, h);
        };
        const bool fine = box % 2 && s % 2;
        const Coord p = fine ? Coord{near(focus.x, lo.x, hi.x), near(focus.y, lo.y, hi.y),
                                     near(focus.z, lo.z, hi.z)}
                             : Coord{pick(lo.x, hi.x), pick(lo.y, hi.y), pick(lo.z, hi.z)};
        ASSERT_TRUE(r.covers(p));
        const int want = reference(octants, p);
        const int32_t got = r.find(p);
        if (want < 0) {
          ASSERT_EQ(got, ModelRegion::kHole) << "seed " << seed << " box " << box;
        } else {
          ASSERT_NE(got, ModelRegion::kHole) << "seed " << seed << " box " << box;
          EXPECT_EQ(r.octant(got), octants[want].o);
          EXPECT_EQ(r.values(got), octants[want].v);
        }
      }
      // Vs bounds over sub-boxes of every size (around the graded point in
      // half the boxes) hold the Vs of every point the reference finds in
      // them (a hole counts as 0).
      for (int b = 0; b < 16; ++b) {
        const int halve = int(rng() % 24);
        const auto span = [&](uint32_t f, uint32_t l, uint32_t h, uint32_t* from, uint32_t* to) {
          const uint32_t c =
              box % 2 ? std::clamp(f, l, h) : l + uint32_t(rng() % (uint64_t{h} - l + 1));
          const uint32_t w = (h - l) >> halve;
          *from = c - std::min(w, c - l), *to = c + std::min(w, h - c);
        };
        Coord bl, bh;
        span(focus.x, lo.x, hi.x, &bl.x, &bh.x);
        span(focus.y, lo.y, hi.y, &bl.y, &bh.y);
        span(focus.z, lo.z, hi.z, &bl.z, &bh.z);
        float vs_lo = 0, vs_hi = 0;
        ASSERT_TRUE(r.vs_bounds(bl, bh, &vs_lo, &vs_hi));
        for (int s = 0; s < 40; ++s) {
          const auto any = [&](uint32_t l, uint32_t h) {
            return s < 8 ? (s & 1 ? h : l) : l + uint32_t(rng() % (uint64_t{h} - l + 1));
          };
          const Coord p{any(bl.x, bh.x), any(bl.y, bh.y), any(bl.z, bh.z)};
          const int want = reference(octants, p);
          const float vs = want < 0 ? 0.0f : octants[want].v[1];
          ASSERT_LE(vs_lo, vs) << "seed " << seed << " box " << box;
          ASSERT_GE(vs_hi, vs) << "seed " << seed << " box " << box;
        }
      }
      const Coord outside{hi.x + 1, lo.y, lo.z};
      if (hi.x + 1 < kRootEdge) {
        EXPECT_FALSE(r.covers(outside));
      }
    }
  }
}

// A model table opened for reading, and a region over the whole root
// loaded from it (the region last: it goes before the table it read).
struct WholeRoot {
  std::unique_ptr<Database> db;
  std::unique_ptr<BTree> table;
  ModelRegion region;
  void open(const std::string& dir) {
    ASSERT_TRUE(Database::open(dir, Database::Mode::kRead, false, &db).ok());
    ASSERT_TRUE(db->open_table(kModelTable, 8 << 20, &table).ok());
  }
  Status load(size_t cap) {
    const Coord all{kRootEdge - 1, kRootEdge - 1, kRootEdge - 1};
    return region.load(*table, {0, 0, 0}, all, 12, cap);
  }
};

TEST(ModelRegion, PastItsCapTheRegionStaysUnloaded) {
  std::mt19937_64 rng(9);
  std::vector<ModelOctant> octants;
  grow(octant_root(), 4, {0, 0, 0}, rng, 1000000, &octants);
  ASSERT_GT(octants.size(), 64u);
  WholeRoot w;
  ASSERT_NO_FATAL_FAILURE(w.open(write_model("cap", octants)));
  ASSERT_TRUE(w.load(64).ok());
  EXPECT_FALSE(w.region.loaded());
  EXPECT_FALSE(w.region.covers({0, 0, 0}));
  ASSERT_TRUE(w.load(octants.size()).ok());
  EXPECT_TRUE(w.region.loaded());
  EXPECT_EQ(w.region.octants(), octants.size());
}

// The cap holds exactly, also where the box's cells each lie inside one
// model octant (found by a floor, not a scan): eight octants of level 1
// under cells of level 2 load with a cap of 8 and not with 7 (the region
// makes room for the cap once and never grows past it).
TEST(ModelRegion, TheCapHoldsForOctantsLargerThanTheCells) {
  std::vector<ModelOctant> octants;
  for (int k = 0; k < 8; ++k) {
    const float vs = 500.0f + 100.0f * float(k);
    octants.push_back({octant_child(octant_root(), k), ModelValues{2 * vs, vs, 2000, 0, 0}});
  }
  WholeRoot w;
  ASSERT_NO_FATAL_FAILURE(w.open(write_model("cap_floors", octants)));
  ASSERT_TRUE(w.load(7).ok());
  EXPECT_FALSE(w.region.loaded());
  ASSERT_TRUE(w.load(8).ok());
  ASSERT_TRUE(w.region.loaded());
  EXPECT_EQ(w.region.octants(), 8u);
  const Coord far{kRootEdge - 1, kRootEdge - 1, kRootEdge - 1};
  EXPECT_EQ(w.region.values(w.region.find(far))[1], 1200.0f);
}

// weaver verify knows a model table: its octants disjoint (as every octant
// table) and its values in range, naming the first octant out of range.
TEST(ModelRegion, VerifyChecksAModelTablesValues) {
  std::mt19937_64 rng(5);
  std::vector<ModelOctant> octants;
  grow(octant_root(), 6, {1000, 2000, 3000}, rng, 1000000, &octants);
  VerifyOptions o;
  VerifyReport r;
  ASSERT_TRUE(verify_database(write_model("verify_good", octants), o, &r).ok());
  EXPECT_TRUE(r.problems.empty()) << r.problems[0];
  EXPECT_EQ(r.records, octants.size());
  ModelOctant& bad = octants[octants.size() / 2];
  bad.v[1] = -3;
  ASSERT_TRUE(verify_database(write_model("verify_bad", octants), o, &r).ok());
  ASSERT_EQ(r.problems.size(), 1u);
  EXPECT_NE(r.problems[0].find("table model: octant " + describe_octant(bad.o) + " has Vs -3"),
            std::string::npos)
      << r.problems[0];
}

}  // namespace
}  // namespace weaver
