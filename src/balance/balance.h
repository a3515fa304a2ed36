// `weaver balance`: the minimal face+edge 2:1 balanced refinement of the
// octant table, out of core, in three parts:
//
//  - closure.h: the octants the balance requires to be resolved, level by
//    level from fine to coarse, each level sorted out of core;
//  - refinement.h: the leaves written in Z-order by sorted append, each
//    split just enough to resolve the required octants inside it; new
//    leaves take their material from the model that built the table (a
//    callback built in balance.cc), or keep their parent's;
//  - check.cc: --check (and verify): the closure without propagation, and
//    the first violation, named.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "db/octant_table.h"
#include "db/table_files.h"
#include "schema/status.h"
#include "util/memory_budget.h"
#include "util/progress.h"

namespace weaver {

class BTree;

struct BalanceOptions {
  MemoryBudget memory;
  bool check_only = false;  // verify only; name the first violation
  // The closure's neighbour generation and sorts share the work among this
  // many threads, and with more than one the refinement's output is written
  // on a thread of its own; the table is the same for any count.
  int threads = 1;
  // Chunks of parents at least this large are shared among the threads
  // (smaller ones cost more to hand out than they take); tests lower it.
  size_t parallel_chunk = size_t{1} << 15;
  // Only the input leaves with keys in [keep_from, keep_to) (and what they
  // are split into) are written: one rank's part of a parallel balance,
  // whose other leaves are its neighbours' (balance_shard.h).
  uint64_t keep_from = 0, keep_to = UINT64_MAX;
  // How: in windows (window_balance.h), or by the closure (closure.h).
  // Auto takes windows, whose threads share no pass (at 1 Hz the second
  // gives 1.7x), and gives up for the closure when a window's layer
  // outweighs its own leaves (coarse leaves among fine ones, as in random
  // refinement: the layers would be read again and again).  Windows that
  // do not fit in the memory even when short fall back to the closure
  // too.  The table is the same every way.
  enum class Algorithm { kAuto, kWindows, kClosure };
  Algorithm algorithm = Algorithm::kAuto;
  uint64_t window_leaves = 0;  // tests: windows at most this long (0: as the memory allows)
  // Model databases to look in, beside DB itself, for the model the octant
  // table names by its identity (--model db:PATH): its new leaves' material.
  std::vector<std::string> model_dirs;
  // The output's page format: as the input's (-1), packed (1) or plain (0).
  // A parallel balance reads its scratch input from plain pages (its many
  // aggregate hits along a ragged boundary decode no packed leaves) and
  // writes its shard packed.
  int output_packed = -1;
  // A rank's balance_shard (weaver-mpi mesh --unbalanced): the octant table
  // is these shards, which the run's rank 0 has staged but not committed.
  std::vector<ShardEntry> staged_octants;
  // Leaves read by the current pass and the fraction done
  // (balance_progress.h); not called by a check.
  ProgressFn progress;
};

// Where balance's memory goes: the shares of options.memory.
struct BalanceMemory {
  explicit BalanceMemory(MemoryBudget budget);

  MemoryPlan plan;
  uint64_t leaf_pool = 0;       // the input leaves, read in order by several cursors
  uint64_t output_pool = 0;     // the output table, written by sorted append
  uint64_t spool_buffer = 0;    // each of the closure's spools (4 per level)
  uint64_t parent_chunk = 0;    // a chunk of parents and its key set
  uint64_t candidate_sort = 0;  // the sorter of a level's candidates
  uint64_t domain_map = 0;      // which coarse cells the leaves cover (domain_map.h)
  uint64_t second_reader = 0;   // the pool of the first scan's second reader (threads > 1)
  uint64_t windows = 0;  // the windows in flight (the closure's chunk, sorter, spools and map)
  MemoryBudget model;    // a model database's readers (modeldb/db_model.h)
  MemoryBudget surface;  // a carved mesh's ground, read again (model/surface.h)
};

struct BalanceResult {
  uint64_t input_leaves = 0, output_leaves = 0;
  // The closure: distinct required octants in the domain; windows: the
  // octants created inside the leaves (those strictly inside one).
  uint64_t required = 0;
  bool by_windows = false;    // balanced in windows, not by the closure
  uint64_t layer_leaves = 0;  // windows: leaves read around them (their layers)
  uint64_t windows = 0;       // windows: how many were written
  uint64_t split = 0;         // input leaves that were split
  LevelCounts levels{};       // of the output
  bool balanced = true;       // check_only: the verdict
  std::string violation;      // check_only: the first violation, named
};

Status balance_octree(const std::string& db_dir, const BalanceOptions& options,
                      BalanceResult* result);
// The check of --check on an octant table already open (a reader's
// snapshot): result->balanced and, if false, result->violation.  Sorter
// scratch goes in a directory under scratch_parent, removed at the end.
// The leaves' pool is the caller's, outside options.memory.
Status check_balance(BTree& leaves, const BalanceOptions& options,
                     const std::string& scratch_parent, BalanceResult* result);

// The finest level with leaves, from the metadata when the writer kept it
// (else kMaxLevel).
int finest_level_bound(BTree& leaves);

}  // namespace weaver
