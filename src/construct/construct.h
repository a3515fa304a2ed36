// `weaver construct`: an octree from a velocity model.  Every leaf satisfies
//   edge <= Vs_min / (freq * ppw)
// where Vs_min is the least Vs of the model over 27 sample points of the leaf
// (corners, edge midpoints, face centres and centre), raised to at least
// --vs-min; and no leaf is finer than needed (its parent breaks the rule).
// Leaves come from depth-first descents of subtrees in Z-order (on worker
// threads, descent.h), each subtree 2:1 balanced in memory against the
// leaves around it (subtree_balance.h, unless --unbalanced), and are written
// by sorted append, each with the material at its centre; memory does not
// grow with the mesh.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "db/database.h"
#include "db/octant_table.h"
#include "model/ground_model.h"
#include "model/surface.h"
#include "schema/octant.h"
#include "schema/status.h"
#include "util/leaf_span.h"
#include "util/memory_budget.h"
#include "util/progress.h"

namespace weaver {

struct ConstructOptions {
  std::string model = "basin";
  std::string grid_file;  // model "grid"
  double freq = 0.5;      // Hz
  double ppw = 10;        // points per wavelength
  double vs_min = 0;      // floor on Vs in the rule (m/s); 0: none
  std::array<double, 3> domain_m = {100000, 100000, 37500};
  // Where the domain's origin lies on the Earth (model/geo_frame.h's text
  // form); "" takes the model's own when it has one.
  std::string geo;
  // Where the domain reaches past the model's box (VelocityModel::outside):
  // refuse (true) or sample the model's edge values there (false, the default).
  bool outside_error = false;
  // The ground (model/surface.h): "" takes an rfile model's own surface
  // and is flat for any other; "flat" is today's box, byte for byte.
  std::string surface;
  SurfaceCrs surface_crs = SurfaceCrs::kFrame;
  // The elevation of z = 0 (metres); NaN: the highest ground rounded up to
  // a tick (0 when flat).  The domain's z is measured down from it.
  double top_elevation = NAN;
  // How the model reads z: "" is elevation for an rfile, depth below the
  // local ground for any other (model/ground_model.h).
  std::string model_z;
  // Leaves the ground crosses are split until their edge is at most this
  // (metres); 0: the wavelength rule alone (its samples in the air taken at
  // the ground beneath).
  double surface_edge_m = 0;
  int min_level = 0, max_level = kMaxLevel;
  MemoryBudget memory;
  // Worker threads visiting subtrees (descent.h); the table is the same for any count.
  int threads = 1;
  // The leaves a subtree's visit holds (its own room) before it is visited
  // again as its 8 children (0: as the budget allows); the table is the
  // same for any (the tests make it small).
  uint64_t subtree_leaves = 0;
  // With subtree_leaves: a pool of this many leaves that subtrees past it
  // may take from (construct/leaf_room.h; 0: none).  The table is the same.
  uint64_t subtree_pool = 0;
  // Packed leaf pages (storage/packed_leaf.h); false writes plain ones.
  bool packed = true;
  // Write the minimal face+edge 2:1 balanced refinement of the octree
  // (subtree_balance.h): the table `weaver balance` would write from the
  // unbalanced one.  False (--unbalanced) writes the descent's leaves as
  // they are.
  bool balanced = true;
  // Settle octants from the model's Vs bounds where they can
  // (VelocityModel::vs_bounds, descent.h); false samples every octant.  The
  // table is the same either way: the tests compare them.
  bool model_bounds = true;
  // Refuse to start when the estimated octree (construct/estimate.h) has
  // more leaves than this, or needs more disk than is free.  5G is ~4x the
  // paper's 2 Hz mesh.
  uint64_t max_elements = 5'000'000'000ull;
  // The run goes on to balance and extract (`weaver mesh`): the disk check
  // counts their tables too.
  bool whole_pipeline = false;
  // One rank's part of a parallel construct (construct_shard): the
  // subtrees whose estimated Z-order share (construct/estimate.h) begins in
  // [shard, shard + 1) / shards.  Ranks cut so own contiguous key ranges,
  // and their shards, in rank order, hold the table a single run writes.
  int shard = 0, shards = 1;
  // Leaves written, and the fraction of the estimate (construct/estimate.h)
  // that lies before the last of them in Z-order.
  ProgressFn progress;
  // A writer already open on the database (else construct opens its own),
  // and whether to stage the table there (Database::stage: `weaver mesh`
  // commits it with the node table) rather than publish it.
  Database* writer = nullptr;
  bool stage = false;
};

// Where construct's memory goes: the shares of options.memory.  The descent
// itself holds one path of octants, whatever the mesh.
struct ConstructMemory {
  // threads: the workers; focused_balance: a balanced construct from a
  // model read from storage (a model database, "db:..."), whose plan counts
  // the balance's buffers where its subtrees are pooled (construct.cc).
  explicit ConstructMemory(MemoryBudget budget, int threads = 1, bool focused_balance = false);
  explicit ConstructMemory(const ConstructOptions& o);

  MemoryPlan plan;
  uint64_t table_pool = 0;  // the octant table, written by sorted append
  uint64_t subtrees = 0;    // leaves of the subtrees in flight (descent.h)
  bool pooled = false;      // the subtrees in flight lend half their rooms to a pool
  uint64_t balance = 0;     // the balance's buffers, a set a worker (subtree_balance.h)
  MemoryBudget model;       // a model database's readers (modeldb/db_model.h)
  uint64_t surface = 0;     // the ground's grid and its pyramid (model/surface.h)
};

// The domain as a union of blocks: resolved before anything is written.
struct ConstructPlan {
  double root_edge_m = 0;  // the root octant's edge
  double tick_m = 0;       // root_edge_m / 2^20
  int block_level = 0;
  std::array<uint32_t, 3> blocks = {1, 1, 1};
  std::array<double, 3> domain_m = {0, 0, 0};  // as covered by the blocks
  bool rounded_up = false;      // no blocks tiled the domain exactly: rounded up to them
  std::string model;            // the model's description
  std::string outside;          // where the domain reaches past the model's box ("": nowhere)
  std::string surface_outside;  // where the domain reaches past the surface's grid ("": nowhere)
  // The ground the mesh follows: surface null when flat.  carved: air is
  // cut away and each leaf carries its solid fraction.
  std::shared_ptr<const Surface> surface;
  std::string surface_source = "flat";
  SurfaceCrs surface_crs = SurfaceCrs::kFrame;
  Ground ground;
  bool carved = false;
  double estimated_elements = 0;          // from a coarse sampling (construct/estimate.h)
  double estimated_disk_bytes = 0;        // at the worst packing of materials
  double estimated_least_disk_bytes = 0;  // at the best
};

struct ConstructResult {
  uint64_t elements = 0;
  LevelCounts levels{};
  double smallest_edge_m = 0, largest_edge_m = 0;
  double worst_ppw = 0;  // the fewest points per wavelength at any leaf (by its Vs_min)
  uint64_t table_bytes = 0;
  uint64_t subtrees = 0;       // visited by the workers (descent.h), and of those
  uint64_t subtrees_over = 0;  // the ones past their leaf room, visited again as 8 children
  // Balanced: the descent's leaves before the balance split some, and the
  // leaves outside the subtrees descended again to balance them against.
  uint64_t descended = 0, neighbours = 0;
  // The descent's leaves written as whole blocks of one level, unjudged
  // one by one (Descent::emit_block).
  uint64_t blocked = 0;
  // Carved: the leaves dropped as wholly above the ground, and the kept
  // leaves the ground crosses (solid fraction below 1).
  uint64_t air = 0, cut = 0;
  // Carved: the box the leaves span and whether they fill it (settled).
  LeafSpan span;
  // The least edge / vp of any leaf (seconds) and its element id: an
  // explicit solver's time step is a Courant number times it.
  double least_dt = HUGE_VAL;
  uint64_t least_dt_element = 0;
};

Status plan_construct(const ConstructOptions& options, ConstructPlan* plan);
Status construct_octree(const std::string& db_dir, const ConstructOptions& options,
                        ConstructPlan* plan, ConstructResult* result);
// One rank's shard of a parallel construct (options.shard of options.shards):
// its leaves written to the new shard file `file` in db_dir
// (db/database.h's create_shard_table) and synced, its metadata the table's
// but for its own level counts; *entry describes it for the manifest.  A
// rank whose part holds no leaf writes no file (entry->records 0).  The
// caller checks the disk (check_construct_fits) and commits the shards.
Status construct_shard(const std::string& db_dir, const ConstructOptions& options,
                       const std::string& file, ConstructPlan* plan, ConstructResult* result,
                       ShardEntry* entry);

}  // namespace weaver
