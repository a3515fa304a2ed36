// The boundary table (boundary/boundary.h) against tests/reference's
// boundary on generated octrees: filled ones (a non-cube block domain,
// random refinement), the same with leaves taken away at random (holes,
// as an imported octree or a carved mesh has), and a graded sphere.
#include "boundary/boundary.h"

#include <gtest/gtest.h>

#include <random>

#include "db/boundary_table.h"
#include "db/database.h"
#include "reference/boundary_reference.h"
#include "test_mesh.h"
#include "test_octrees.h"
#include "test_util.h"

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
  BoundaryResult r;
  ASSERT_OK(build_boundary(db, BoundaryOptions{}, &r));
  EXPECT_EQ(r.filled, filled);
  const auto want = reference::boundary(sorted);
  const auto got = stored_boundary(db);
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) {
    ASSERT_TRUE(got[i] == want[i]) << "record " << i << ": element " << want[i].element << " face "
                                   << want[i].face << " part " << want[i].part;
  }
  EXPECT_EQ(r.faces, want.size());
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

}  // namespace
}  // namespace weaver
