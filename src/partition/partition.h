// `weaver partition`: the elements of a mesh cut into N parts for N solver
// processes, stored with the database (db/partition_table.h) for export and
// later stages, and a report of each part: elements, owned and shared nodes,
// and the faces it shares with other parts (the edge cut of the dual graph).
//
//   sfc    contiguous ranges of the Z-order (element ids), balanced by count
//          or by a weight (--weight level: 2^(level - coarsest), the cost of
//          local time stepping, where finer elements step more often)
//   graph  a part per element from a file of one part per line in element id
//          order: what gpmetis writes for the dual graph of
//          `weaver export --format metis` (the command runs it)
//
// A node is shared when elements of two or more parts use it, and owned by
// the lowest of those parts.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "mesh/part_map.h"
#include "schema/status.h"
#include "util/memory_budget.h"
#include "util/progress.h"

namespace weaver {

struct PartitionOptions {
  uint32_t parts = 2;
  enum class Method { kSfc, kGraph } method = Method::kSfc;
  enum class Weight { kNone, kLevel } weight = Weight::kNone;
  std::string part_file;  // kGraph: one part per line, in element id order
  bool store = true;      // false: only report
  MemoryBudget memory;
  ProgressFn progress;  // elements placed, then reported
};

struct PartStats {
  uint64_t elements = 0, weight = 0;
  uint64_t owned_nodes = 0, shared_nodes = 0;
  uint64_t cut_faces = 0;  // faces shared with elements of other parts
};

struct PartitionReport {
  std::vector<PartStats> parts;
  uint64_t edge_cut = 0;      // element pairs across parts sharing a face
  uint64_t shared_nodes = 0;  // nodes used by more than one part
  uint64_t runs = 0;          // records of the partition table
};

struct PartitionMemory {
  explicit PartitionMemory(MemoryBudget budget);
  MemoryPlan plan;
  uint64_t octant_pool = 0, node_pool = 0;
  uint64_t table_pool = 0;  // the stored partition's table
  uint64_t node_sort = 0;   // (node, part) pairs of the report
};

// Computes the partition, stores it unless !options.store, and reports it.
Status partition_mesh(const std::string& db_dir, const PartitionOptions& options,
                      PartitionReport* report);

}  // namespace weaver
