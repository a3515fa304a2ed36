// A database holding the mesh of given leaves (imported, then extracted),
// for the tests of what reads a mesh: export, partition, query.
#pragma once

#include <algorithm>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "db/database.h"
#include "extract/extract.h"
#include "gen/octree_gen.h"
#include "import/import.h"
#include "import/octant_text.h"
#include "test_util.h"

namespace weaver::testing {

// The bytes of the octant table of the database in db_dir, to compare the
// tables that different thread counts or budgets write.
inline std::string table_bytes(const std::string& db_dir) {
  std::unique_ptr<Database> db;
  EXPECT_OK(Database::open(db_dir, Database::Mode::kRead, false, &db));
  std::ifstream in(db->table_path(kOctantTable), std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Imports and extracts leaves into dir/db; returns the database path.
inline std::string build_mesh(const std::vector<Octant>& leaves, const TempDir& dir) {
  const std::string db = dir.file("db"), text = dir.file("o.txt");
  EXPECT_OK(write_octant_text(text, leaves, ""));
  ImportResult ir;
  EXPECT_OK(import_octants(db, text, ImportOptions{}, &ir));
  ExtractResult er;
  EXPECT_OK(extract_mesh(db, ExtractOptions{}, &er));
  return db;
}

// A small graded octree (a sphere refined from level 2 to 5), sorted in key
// order: the everyday mesh of the query and shell tests.
inline std::vector<Octant> small_sphere() {
  GenOptions g;
  g.kind = GenOptions::Kind::kSphere;
  g.level = 2;
  g.max_level = 5;
  g.radius = 0.27;
  std::vector<Octant> leaves;
  EXPECT_OK(generate_octree(g, &leaves));
  std::sort(leaves.begin(), leaves.end(),
            [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
  return leaves;
}

}  // namespace weaver::testing
