// `weaver balance`: the minimal face+edge 2:1 balanced refinement of the
// octant table, out of core.
//
// Every leaf (or required octant) q at level l requires the face and edge
// neighbours of its parent, at level l-1, to be resolved: covered by leaves
// of level >= l-1.  These requirements ripple from fine to coarse, one level
// at a time; each level's set is sorted and deduplicated out of core, and
// octants outside the domain are dropped (they hold no leaves to balance
// against).  Every requirement is necessary, so the result is minimal: each
// leaf is kept or split just enough to resolve the required octants inside
// it.  Leaves are written in Z-order by sorted append; split children take
// their material from the model that built the table, or from the parent.
#pragma once

#include <cstdint>
#include <string>

#include "db/octant_table.h"
#include "schema/status.h"

namespace weaver {

struct BalanceOptions {
  uint64_t memory_bytes = 256ull << 20;
  bool check_only = false;  // verify only; name the first violation
};

struct BalanceResult {
  uint64_t input_leaves = 0, output_leaves = 0;
  uint64_t required = 0;   // distinct required octants in the domain
  uint64_t split = 0;      // input leaves that were split
  LevelCounts levels{};    // of the output
  bool balanced = true;    // check_only: the verdict
  std::string violation;   // check_only: the first violation, named
};

Status balance_octree(const std::string& db_dir, const BalanceOptions& options,
                      BalanceResult* result);
// The check of --check on an octant table already open (a reader's
// snapshot): result->balanced and, if false, result->violation.  Sorter
// scratch goes in a directory under scratch_parent, removed at the end.
class BTree;
Status check_balance(BTree& leaves, const BalanceOptions& options,
                     const std::string& scratch_parent, BalanceResult* result);

}  // namespace weaver
