// `weaver verify`: checks a database from the pages up.
//
// Storage: every page of every table (checksums, key order, separators,
// subtree counts, the header's record count), octant keys decode to valid,
// non-overlapping octants whose per-level counts match the metadata, node
// keys are node coordinates with a known kind.
//
// Mesh (when the octants and nodes tables are both present): the octree is
// 2:1 balanced; every node, classified again from the leaves around it, has
// the kind stored for it; every element corner is a node and every node a
// corner of some element; the anchors of every dangling node exist and are
// anchored.  The classification is independent of the extractor: it looks
// at the up to 8 leaves touching the node (one aggregate hit each).
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
  int threads = 1;  // the node check's share of nodes a thread (the same report for any count)
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
