// A database holding the mesh of given leaves (imported, then extracted),
// for the tests of what reads a mesh: export, partition, query.
#pragma once

#include <string>
#include <vector>

#include "extract/extract.h"
#include "import/import.h"
#include "import/octant_text.h"
#include "test_util.h"

namespace weaver::testing {

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

}  // namespace weaver::testing
