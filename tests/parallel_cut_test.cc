// cut_equal_runs (db/octant_table.h), the parts weaver-mpi's balance and
// extract give their ranks, against a reference that reads every key: rank
// r begins at the first position at or after n*r/ranks whose leaf is not a
// later sibling of the leaf before it, so no family is split between ranks.
#include <gtest/gtest.h>

#include <vector>

#include "db/database.h"
#include "db/octant_table.h"
#include "sample_octrees.h"
#include "storage/btree.h"
#include "test_util.h"

namespace weaver {
namespace {

using testing::TempDir;

bool reference_siblings(uint64_t a, uint64_t b) {
  const Octant x = octant_from_key(a), y = octant_from_key(b);
  return x.level > 0 && x.level == y.level && octant_parent(x) == octant_parent(y);
}

// What cut_equal_runs should give, from every key of the table.
void reference_cut(const std::vector<uint64_t>& keys, int ranks, std::vector<uint64_t>* first,
                   std::vector<uint64_t>* start) {
  const uint64_t n = keys.size();
  first->assign(ranks + 1, UINT64_MAX);
  start->assign(ranks + 1, UINT64_MAX);
  for (int r = 0; r < ranks; ++r) {
    uint64_t pos = n * r / ranks;
    while (pos > 0 && pos < n && reference_siblings(keys[pos - 1], keys[pos])) ++pos;
    if (pos >= n) break;
    (*first)[r] = keys[pos];
    (*start)[r] = r == 0 ? 0 : octant_key_morton(keys[pos]);
  }
}

TEST(CutEqualRuns, RunsBeginWhereNoFamilyIsSplitAsTheReferenceFinds) {
  TempDir dir;
  std::vector<std::string> octrees = {testing::two_family_octree(dir, "families")};
  for (uint64_t seed : {1, 2, 3}) {
    octrees.push_back(testing::random_octree(dir, "random" + std::to_string(seed), seed,
                                             4 + 3 * seed, seed == 2, 3000));
  }
  for (size_t i = 0; i < octrees.size(); ++i) {
    const std::string& db = octrees[i];
    std::unique_ptr<Database> d;
    ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &d));
    std::unique_ptr<BTree> t;
    ASSERT_OK(d->open_table(kOctantTable, 1 << 20, &t));
    const std::vector<uint64_t> keys = testing::octant_table_keys(db);
    uint64_t moved = 0;
    for (int ranks : {1, 2, 3, 4, 7, 8, 9, 16, 100, 5000}) {
      SCOPED_TRACE("octree " + std::to_string(i) + " on " + std::to_string(ranks) + " ranks");
      std::vector<uint64_t> first, start, want_first, want_start;
      ASSERT_OK(cut_equal_runs(*t, ranks, &first, &start));
      reference_cut(keys, ranks, &want_first, &want_start);
      EXPECT_EQ(first, want_first);
      EXPECT_EQ(start, want_start);
      for (int r = 0; r < ranks; ++r) moved += first[r] != keys[keys.size() * r / ranks];
    }
    EXPECT_GT(moved, 0u);  // some cut did fall inside a family
  }
}

}  // namespace
}  // namespace weaver
