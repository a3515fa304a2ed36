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
#include "util/memory_budget.h"
#include "util/progress.h"

namespace weaver {

struct ExportOptions {
  std::string nodes_path;     // empty: skip
  std::string elements_path;  // empty: skip
  MemoryBudget memory;
  // Rows written (nodes, then elements) and their fraction of all rows.
  ProgressFn progress;
};

// Where export's memory goes: the shares of options.memory.
struct ExportMemory {
  explicit ExportMemory(MemoryBudget budget);

  MemoryPlan plan;
  uint64_t node_pool = 0;    // the node table: corners and anchors are found in it by key
  uint64_t octant_pool = 0;  // the octant table, read in order
};

struct ExportResult {
  uint64_t nodes = 0, elements = 0;
};

Status export_csv(const std::string& db_dir, const ExportOptions& options, ExportResult* result);

}  // namespace weaver
