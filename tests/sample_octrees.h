// Octrees imported into test databases and read back, shared by the tests
// of import and of the parallel stages.
#pragma once

#include <string>
#include <vector>

#include "db/database.h"
#include "db/octant_table.h"
#include "gen/octree_gen.h"
#include "import/import.h"
#include "import/octant_text.h"
#include "schema/octant.h"
#include "storage/btree.h"
#include "test_util.h"

namespace weaver::testing {

// octants imported into a new database, dir/name.
inline std::string imported_octree(const TempDir& dir, const std::string& name,
                                   const std::vector<Octant>& octants) {
  const std::string text = dir.file(name + ".txt"), db = dir.file(name);
  EXPECT_OK(write_octant_text(text, octants, ""));
  ImportResult ir;
  EXPECT_OK(import_octants(db, text, ImportOptions{}, &ir));
  return db;
}

// A random octree imported into a new database at db: seed, finest
// level, and a stretch of its leaves cut out (a hole) when `hole`; on a
// domain of 3 x 2 x 1 blocks of level 2 (not a cube).
inline std::string random_octree(const TempDir& dir, const std::string& name, uint64_t seed,
                                 int max_level, bool hole, uint64_t leaves) {
  GenOptions g;
  g.seed = seed;
  g.leaves = leaves;
  g.max_level = max_level;
  g.blocks[0] = 3, g.blocks[1] = 2, g.blocks[2] = 1;
  g.block_level = 2;
  std::vector<Octant> octants;
  EXPECT_OK(generate_octree(g, &octants));
  if (hole)
    octants.erase(octants.begin() + octants.size() / 4, octants.begin() + octants.size() / 3);
  return imported_octree(dir, name, octants);
}

// The root's children with the second cut into eight: 15 leaves, so that
// runs that keep families together (cut_equal_runs) leave ranks without
// leaves between ranks with leaves (on 7 or 8 ranks) and at the end.
inline std::string two_family_octree(const TempDir& dir, const std::string& name) {
  std::vector<Octant> octants;
  for (int k = 0; k < 8; ++k) {
    const Octant child = octant_child(octant_root(), k);
    if (k != 1) octants.push_back(child);
    for (int j = 0; k == 1 && j < 8; ++j) octants.push_back(octant_child(child, j));
  }
  return imported_octree(dir, name, octants);
}

// Every key of db's octant table, in order.
inline std::vector<uint64_t> octant_table_keys(const std::string& db) {
  std::unique_ptr<Database> d;
  std::unique_ptr<BTree> t;
  EXPECT_OK(Database::open(db, Database::Mode::kRead, false, &d));
  EXPECT_OK(d->open_table(kOctantTable, 1 << 20, &t));
  std::vector<uint64_t> keys;
  BTreeCursor c;
  EXPECT_OK(t->seek_cursor(0, &c));
  while (c.valid()) {
    keys.push_back(c.key());
    EXPECT_OK(c.next());
  }
  return keys;
}

}  // namespace weaver::testing
