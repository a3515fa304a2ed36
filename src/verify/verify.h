// `weaver verify`: checks a database from the pages up.
//
// Storage: every page of every table (checksums, key order, separators,
// subtree counts, the header's record count), octant keys decode to valid,
// non-overlapping octants whose per-level counts match the metadata, node
// keys are node coordinates with a known kind.
//
// Mesh (when the octants and nodes tables are both present): the octree is
// 2:1 balanced; every node has the kind stored for it; every element corner
// is a node and every node a corner of some element; the anchors of every
// dangling node exist and are anchored.  By default the nodes are derived
// again by the extractor's bucket sort (derive_nodes) and compared with the
// table in key order, a node that differs then checked alone for the reason;
// with `independent`, every node is classified again from the up to 8 leaves
// touching it (one aggregate hit each), independently of the extractor.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "schema/status.h"
#include "util/memory_budget.h"
#include "util/progress.h"

namespace weaver {

struct VerifyOptions {
  MemoryBudget memory;
  bool mesh = true;          // also check the mesh invariants
  size_t max_problems = 20;  // stop collecting after this many
  int threads = 1;  // for the storage, boundary and node checks (the same report on any count)
  // Classify every node again from the leaves around it (8 lookups a node),
  // independently of the extractor's code, rather than compare the table
  // with the nodes the extractor's bucket sort derives again.
  bool independent = false;
  std::function<void(const std::string& line)> progress;  // one line per finished check
  // The mesh check's nodes: checked, and their fraction of the node table
  // (first called with 0 when the node check starts; from one thread).
  ProgressFn nodes_progress;
};

// Where verify's memory goes: the shares of options.memory.
struct VerifyMemory {
  explicit VerifyMemory(MemoryBudget budget);

  MemoryPlan plan;
  uint64_t table_pool = 0;     // the storage check, one table at a time
  uint64_t octant_pool = 0;    // the mesh check: leaves found by aggregate hits
  uint64_t node_pool = 0;      // the mesh check: nodes read in order and found by key
  MemoryBudget balance_check;  // the balance check's own budget (balance.h)
  MemoryBudget derive;         // after it, the same share: the nodes derived again
  // A carved mesh's surface, read again: the storage check's share, free
  // again by then (the ground check runs after it).
  uint64_t surface = 0;
};

struct VerifyReport {
  std::vector<std::string> problems;  // each names table, page or key
  uint64_t tables = 0, records = 0, pages = 0;
  bool mesh_checked = false;
  uint64_t elements = 0, nodes = 0, dangling = 0, corners = 0;
  bool ok() const { return problems.empty(); }
};

// Problems found go into the report; the returned status is an error only
// when the check itself could not run (say, the directory is missing).
Status verify_database(const std::string& db_dir, const VerifyOptions& options,
                       VerifyReport* report);

}  // namespace weaver
