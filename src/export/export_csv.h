// `weaver export`: the mesh as the flat CSV files of DESIGN.md, streamed
// (rows in id order; nothing but a page cache and a line buffer in memory).
//   nodes.csv     id,x,y,z,kind,a0,a1,a2,a3
//   elements.csv  id,x,y,z,level,n0,n1,n2,n3,n4,n5,n6,n7
// Node ids of corners and anchors are ranks in the node table.  Each file is
// written beside its final name and renamed into place when complete.
#pragma once

#include <cstdint>
#include <string>

#include "schema/status.h"

namespace weaver {

struct ExportOptions {
  std::string nodes_path;     // empty: skip
  std::string elements_path;  // empty: skip
  uint64_t memory_bytes = 256ull << 20;
};

struct ExportResult {
  uint64_t nodes = 0, elements = 0;
};

Status export_csv(const std::string& db_dir, const ExportOptions& options, ExportResult* result);

}  // namespace weaver
