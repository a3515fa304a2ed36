// The boundary table (boundary/boundary.h) against tests/reference's
// boundary on generated octrees: filled ones (a non-cube block domain,
// random refinement), the same with leaves taken away at random (holes,
// as an imported octree or a carved mesh has), and a graded sphere.
#include "boundary/boundary.h"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "db/boundary_table.h"
#include "db/database.h"
#include "reference/boundary_reference.h"
#include "test_mesh.h"
#include "test_octrees.h"
#include "test_util.h"
#include "verify/verify.h"

namespace weaver {
namespace {

std::vector<reference::BoundaryFace> stored_boundary(const std::string& db_dir) {
  std::vector<reference::BoundaryFace> out;
  std::unique_ptr<Database> db;
  EXPECT_OK(Database::open(db_dir, Database::Mode::kRead, false, &db));
  std::unique_ptr<BTree> t;
  EXPECT_OK(db->open_table(kBoundaryTable, 1 << 20, &t));
  BTreeCursor c;
  EXPECT_OK(t->seek_cursor(0, &c));
  while (c.valid()) {
    out.push_back({boundary_element(c.key()), boundary_face(c.key()), boundary_part(c.key()),
                   int(static_cast<uint8_t>(c.payload()[0]))});
    EXPECT_OK(c.next());
  }
  return out;
}

void expect_boundary_matches(const std::vector<Octant>& leaves, bool filled) {
  testing::TempDir dir;
  std::vector<Octant> sorted = leaves;
  std::sort(sorted.begin(), sorted.end(),
            [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
  const std::string db = testing::build_mesh(sorted, dir);
  const auto want = reference::boundary(sorted);
  // One thread; two; three whose later ones hold 7 records at most, so
  // that the first derives the rest of their runs.
  for (const auto& [threads, held] : {std::pair<int, uint64_t>{1, 0}, {2, 0}, {3, 7}}) {
    SCOPED_TRACE("threads " + std::to_string(threads) + ", held " + std::to_string(held));
    BoundaryOptions o;
    o.threads = threads, o.held_records = held;
    BoundaryResult r;
    ASSERT_OK(build_boundary(db, o, &r));
    EXPECT_EQ(r.filled, filled);
    const auto got = stored_boundary(db);
    ASSERT_EQ(got.size(), want.size());
    for (size_t i = 0; i < want.size(); ++i) {
      ASSERT_TRUE(got[i] == want[i]) << "record " << i << ": element " << want[i].element
                                     << " face " << want[i].face << " part " << want[i].part;
    }
    EXPECT_EQ(r.faces, want.size());
    EXPECT_EQ(r.elements, sorted.size());
  }
}

TEST(Boundary, MatchesTheReferenceOnFilledAndHoledOctrees) {
  const int rounds = testing::scaled(6, 2);
  for (int seed = 1; seed <= rounds; ++seed) {
    SCOPED_TRACE(seed);
    const std::vector<Octant> full = testing::random_balanced(seed, 3, 2, 1 + seed % 2, 2, 300, 6);
    ASSERT_NO_FATAL_FAILURE(expect_boundary_matches(full, true));
    // Holes: what remains of a balanced octree stays balanced.
    std::mt19937_64 rng(seed);
    std::vector<Octant> holed;
    for (const Octant& o : full) {
      if (rng() % 5 != 0) holed.push_back(o);
    }
    ASSERT_NO_FATAL_FAILURE(expect_boundary_matches(holed, false));
  }
  ASSERT_NO_FATAL_FAILURE(expect_boundary_matches(testing::small_sphere(), true));
}

// Replaces db's boundary table by `records` (key, kind), as a writer would.
void replace_boundary(const std::string& db_dir,
                      const std::vector<std::pair<uint64_t, uint8_t>>& records) {
  std::unique_ptr<Database> db;
  ASSERT_OK(Database::open(db_dir, Database::Mode::kWrite, false, &db));
  TableOptions t;
  t.key_kind = KeyKind::kNode;
  std::string error;
  t.schema = *RecordSchema::parse(kBoundarySchema, &error);
  std::unique_ptr<BTree> table;
  std::string file;
  ASSERT_OK(db->create_table(kBoundaryTable, t, 1 << 20, &table, &file));
  Status st;
  for (const auto& [key, kind] : records) {
    if (st.ok()) st = table->append(key, reinterpret_cast<const std::byte*>(&kind));
  }
  ASSERT_OK(db->publish(kBoundaryTable, file, table, st));
}

std::vector<std::string> verify_problems(const std::string& db, int threads = 1) {
  VerifyOptions o;
  o.threads = threads;
  VerifyReport r;
  EXPECT_OK(verify_database(db, o, &r));
  return r.problems;
}

// weaver verify derives the boundary again and names every record that
// differs: a face left out, one too many, one of the wrong kind.
TEST(Boundary, VerifyNamesEveryRecordThatDiffersFromTheOctants) {
  testing::TempDir dir;
  std::vector<Octant> leaves = testing::random_balanced(3, 3, 2, 1, 2, 300, 6);
  std::mt19937_64 rng(3);
  std::vector<Octant> holed;
  for (const Octant& o : leaves) {
    if (rng() % 5 != 0) holed.push_back(o);
  }
  std::sort(holed.begin(), holed.end(),
            [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
  const std::string db = testing::build_mesh(holed, dir);
  BoundaryResult r;
  ASSERT_OK(build_boundary(db, BoundaryOptions{}, &r));
  EXPECT_TRUE(verify_problems(db).empty());

  std::vector<std::pair<uint64_t, uint8_t>> records;
  for (const auto& f : stored_boundary(db)) {
    records.push_back({boundary_key(f.element, f.face, f.part), uint8_t(f.kind)});
  }
  ASSERT_GT(records.size(), 10u);
  auto tampered = records;
  const uint64_t dropped = tampered[3].first, flipped = tampered[7].first;
  tampered.erase(tampered.begin() + 3);
  tampered[6].second ^= 1;                                      // records[7], one place earlier now
  const uint64_t extra = boundary_key(holed.size() + 5, 0, 0);  // past every element
  tampered.push_back({extra, 0});
  ASSERT_NO_FATAL_FAILURE(replace_boundary(db, tampered));
  const std::vector<std::string> problems = verify_problems(db);
  auto names = [&](uint64_t key, const std::string& what) {
    const std::string where = "element " + std::to_string(key >> 6) + " face " +
                              std::to_string(key >> 3 & 7) + " part " + std::to_string(key & 7);
    for (const std::string& p : problems) {
      if (p.find(where) != std::string::npos && p.find(what) != std::string::npos) return true;
    }
    return false;
  };
  EXPECT_EQ(problems.size(), 3u);
  EXPECT_EQ(verify_problems(db, 3), problems);  // the boundary derived on three threads
  EXPECT_TRUE(names(dropped, "is not stored"));
  EXPECT_TRUE(names(flipped, "is stored as kind"));
  EXPECT_TRUE(names(extra, "is not a boundary"));

  // The table as it was verifies again.
  ASSERT_NO_FATAL_FAILURE(replace_boundary(db, records));
  EXPECT_TRUE(verify_problems(db).empty());
}

}  // namespace
}  // namespace weaver
