// `weaver extract`: the mesh (nodes, their kinds; elements are the leaves)
// from a balanced octant table, out of core, by either of two algorithms
// that write the same node table:
//
//  - kSort, the two-level bucket sort of Tu & O'Hallaron (section 4;
//    extract_sort.cc, bucket_worker.cc, extract_parallel.cc): the leaves are
//    read once in Z-order in high-level buckets (aligned octants of one
//    level); each leaf's 8 corners are merged in the bucket's hash table,
//    corners on a later bucket's side are spilled to it (spill_store.h), and
//    each node is classified from the cells around it (node_classifier.h).
//    Buckets are written in Z-order, by sorted append, whatever the threads.
//  - kSearch, the conventional baseline (section 3; extract_search.cc): every
//    element vertex is searched for in a scratch node store (a B+tree as in
//    the paper, or the LSM) and inserted when new; the store is then read in
//    order, numbered and classified.
//
// extract.cc holds the entry point, the memory layout and the bucketing
// policy (which bucket level a budget affords).
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "db/database.h"
#include "extract/spill_store.h"
#include "schema/status.h"
#include "util/memory_budget.h"
#include "util/progress.h"
#include "util/rank_exchange.h"

namespace weaver {

struct ExtractOptions {
  // kSort: the two-level bucket sort.  kSearch: the conventional baseline
  // (a node B-tree searched for every element vertex; paper, section 3).
  // Both produce the same node table.
  enum class Algorithm { kSort, kSearch };
  Algorithm algorithm = Algorithm::kSort;
  // The node store of kSearch: the B+tree, as in the paper, or the LSM.
  enum class Store { kBTree, kLsm };
  Store store = Store::kBTree;
  MemoryBudget memory;
  // Worker threads for the sort algorithm; the output is the same for any count.
  int threads = 1;
  // How the sort cuts the leaves into high-level buckets (bucket_worker.h).
  // kLeaves: runs of about bucket_leaves leaves each (0: as many as the
  // bucket share of the budget holds, up to 8192 a MiB of the core's L2
  // cache and 16384 at most: extract.cc), cut at
  // aligned boundaries; buckets then hold the same number of leaves however
  // the octree is graded.  kLevel: the paper's aligned octants of
  // bucket_level (-1: the coarsest level whose bucket, filled with leaves of
  // the finest level present, fits the share: its S2).
  enum class Buckets { kLeaves, kLevel };
  Buckets buckets = Buckets::kLeaves;
  uint64_t bucket_leaves = 0;
  int bucket_level = -1;
  // Packed leaf pages for the node table (storage/packed_leaf.h); false writes plain ones.
  bool packed = true;
  // A writer already open on the database (else extract opens its own):
  // its octant table may be staged (Database::stage), and then goes live
  // with the node table.
  Database* writer = nullptr;
  // Stage the node table in the writer too (Database::stage) rather than
  // commit: a later table's commit (weaver mesh's boundary) makes them all
  // live at once.
  bool stage = false;
  // A rank's extract_shard (weaver-mpi mesh): the octant table is these
  // shards, which the run's rank 0 has staged but not committed.
  std::vector<ShardEntry> staged_octants;
  // Elements done, and their fraction of the octant table (sort only).
  ProgressFn progress;
};

// Where extraction's memory goes: the shares of options.memory.  Fields an
// algorithm does not use stay 0.
struct ExtractMemory {
  explicit ExtractMemory(const ExtractOptions& options);

  MemoryPlan plan;
  uint64_t octant_pool = 0;       // the octant table read in order
  uint64_t node_pool = 0;         // the node table written by sorted append
  uint64_t classifier_cache = 0;  // each worker's NodeClassifier's cache of leaves
  // kSort:
  uint64_t spill = 0;        // spilled pixels held in memory before a file
  uint64_t bucket = 0;       // one worker's bucket: its leaves and hash table
  uint64_t worker_pool = 0;  // threads > 1: each worker's octant table pool
  uint64_t in_flight = 0;    // threads > 1: buckets read ahead of the workers
  // kSearch:
  uint64_t search_store = 0;  // the scratch node store
};

// Where the sort algorithm's nodes go, a bucket at a time in key order:
// their keys and kinds (a NodeKind a byte).
using NodeBatchSink = std::function<Status(const uint64_t* keys, const std::byte* kinds, size_t n)>;

struct ExtractResult {
  uint64_t elements = 0;
  uint64_t nodes = 0, anchored = 0, edge = 0, face = 0;
  int bucket_level = -1;       // kLevel: the level used
  uint64_t bucket_leaves = 0;  // kLeaves: the leaves aimed at per bucket
  uint64_t buckets = 0;
  uint64_t spilled = 0;          // nodal pixels handed to a later bucket
  uint64_t spilled_to_disk = 0;  // of those, the ones that went through a file
  uint64_t node_table_bytes = 0;
  uint64_t search_tree_bytes = 0;  // search: the node B-tree with element codes
};

// Reads the octant table of db_dir, writes its node table.  Refuses an octree
// with overlapping octants or one that is not face+edge 2:1 balanced, naming
// two offending octants; the database is then left as it was.
Status extract_mesh(const std::string& db_dir, const ExtractOptions& options,
                    ExtractResult* result);

// The node records of db's octant table as the sort algorithm derives them
// (those extract_mesh writes, byte for byte), handed to `out` instead of
// written: weaver verify compares them with the stored table.  Spills go
// under scratch_dir (created and removed; nothing is written to db).
// REQUIRES: the octree is balanced (an unbalanced one gives wrong kinds).
Status derive_nodes(const Database& db, const ExtractOptions& options,
                    const std::string& scratch_dir, const NodeBatchSink& out,
                    ExtractResult* result);

// One rank's part of a parallel extract (weaver-mpi; the sort algorithm).
// The balanced leaves are cut into `ranks` runs of equal count; rank r owns
// the node keys from its first leaf's Morton code to the next rank's (the
// last rank: to the end), so a node's owner follows from its key alone.
// Every leaf around a node has a Morton code no larger than the node's, so
// the leaves around a rank's nodes are its own and the ghost layer: the
// leaves of earlier ranks whose far faces reach into its range
// (ghost_layer.h).  Each rank sends its leaves to the ranks whose ghosts
// they are, once, before any bucket runs, through `exchange` (a collective
// every rank calls exactly once, also after an error, with nothing to send).
// Then it runs the bucket sort over its own leaves, the ghosts' corners in
// its range waiting in its spill store and the ghosts answering the
// classifier's lookups before its range, and writes its nodes to the new
// shard file `file` (synced; *entry describes it; records 0 and no file when
// it owns none).  A rank reads only its own run of leaves from the database
// (and the shards' counts, for the cut).  The caller commits the shards.
struct ShardExchangeCounts {
  uint64_t ghosts_sent = 0, ghosts_received = 0;  // leaves
  uint64_t bytes_sent = 0, bytes_received = 0;
};
Status extract_shard(const std::string& db_dir, const ExtractOptions& options, int rank, int ranks,
                     const std::string& file, const RankExchange& exchange, ExtractResult* result,
                     ShardEntry* entry, ShardExchangeCounts* counts);

}  // namespace weaver
