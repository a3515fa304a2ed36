// `weaver boundary` (and the last step of `weaver mesh`): the boundary
// table (db/boundary_table.h) from the octant table: the element faces, or
// quarters of faces, that a solver must treat as a boundary.
//
// Two scans of the octant table in key order.  The first finds the box the
// leaves span and whether they fill it (their volumes add up to its); a
// caller that knows the box they fill skips it (known_filled_box).  The
// second visits each element's six faces:
//   - a face on the box's side is a boundary: the free surface where it
//     faces up (z-, the domain's top), else a domain side (absorbing);
//   - where the leaves fill the box, nothing else is;
//   - otherwise (air cut away, or an imported octree's holes) a face whose
//     neighbourhood could hold a hole asks the octant table what lies
//     across it (mesh/face_neighbors.h): nothing, and the whole face is
//     free surface; finer elements on some of its quarters only, and the
//     others are.  A mesh built with a ground surface rules out the
//     elements whose neighbourhood lies wholly below the ground, and of
//     the others the faces whose box across lies wholly below it (the
//     surface read again, as the octant table's metadata names it).
// The same pass finds the element of least edge / vp (an explicit solver's
// time step is a Courant number times it), for 'weaver stat'.
// Any face up (z-) with nothing across it is free surface; any other face
// inside the box with nothing across it faces the air too.  The table is
// written by sorted append and committed (publish) on its own.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "db/database.h"
#include "db/table_files.h"
#include "schema/status.h"
#include "util/leaf_span.h"
#include "util/memory_budget.h"
#include "util/progress.h"

namespace weaver {

struct BoundaryOptions {
  MemoryBudget memory;
  // Threads for the scan (build_boundary): the elements cut into equal
  // ranges; the table is the same for any count.
  int threads = 1;
  // The records a thread past the first may hold until its turn (0: as
  // the budget allows); past it, the first thread derives the rest.
  uint64_t held_records = 0;
  bool packed = true;
  ProgressFn progress;         // elements visited, and their share
  Database* writer = nullptr;  // a writer already open on the database
  // The least edge / vp and its element when the caller knows them (weaver
  // mesh: construct found them): the scan then reads keys alone.  0: found
  // here, from the leaves' vp.
  double known_least_dt = 0;
  uint64_t known_least_dt_element = 0;
  // The box the leaves span, in ticks, and whether they fill it, when the
  // caller knows (weaver mesh: construct's blocks where it cut no air, else
  // the span of the leaves it wrote): the first scan, which finds them, is
  // skipped.
  bool known_box = false;
  bool box_filled = true;
  std::array<uint32_t, 3> box_lo{}, box_hi{};
  // boundary_shard (weaver-mpi mesh): the octant table is these shards,
  // which the run's rank 0 has staged but not committed.
  std::vector<ShardEntry> staged_octants;
};

struct BoundaryResult {
  uint64_t elements = 0;
  uint64_t faces = 0;         // records: whole faces and quarters
  uint64_t quarters = 0;      // of those, quarters
  uint64_t free_surface = 0;  // of those, facing the air or the top
  bool filled = true;         // the leaves fill the box they span
  uint64_t asked = 0;         // elements whose neighbours were looked up
  uint64_t table_bytes = 0;
  // Met on the way (a mesh with material): the least edge / vp of any
  // element (seconds) and its id, kept in the table's metadata too.
  double least_dt = 0;
  uint64_t least_dt_element = 0;
};

Status build_boundary(const std::string& db_dir, const BoundaryOptions& options,
                      BoundaryResult* result);

// One rank's all-gather (weaver-mpi): its text out, every rank's in rank
// order back.
using RankAllGather = std::function<Status(const std::string& mine, std::vector<std::string>* all)>;

// weaver-mpi mesh: rank `rank` of `ranks` writes the boundary records of the
// elements with ids [n rank / ranks, n (rank + 1) / ranks) of db_dir's
// octant table (n its size) as shard file `file`, synced and described in
// *entry (no file when it holds no record).  The box the leaves span and
// whether they fill it, the least edge / vp and the counts in the table's
// metadata are every rank's together, gathered twice, so that the shards
// compact to the table build_boundary writes, byte for byte.  A rank that
// fails still takes part in both gathers (sending ""), and the others then
// drop their files and return OK: the failed rank's error is the one to
// report.  The caller commits the shards.
Status boundary_shard(const std::string& db_dir, const BoundaryOptions& options, int rank,
                      int ranks, const std::string& file, const RankAllGather& all_gather,
                      BoundaryResult* result, ShardEntry* entry);

// `weaver verify`: the boundary records derived again from the octant
// table against the `stored` table, record by record; each difference (up
// to max_problems) named by element, face and part in *problems.  One
// thread a handle of the octant table in `octants` (as build_boundary's
// threads, the later ones holding up to `held` records each).  A carved
// mesh's surface is read within `surface`.  `span`: what the octant
// table's leaves span, settled, where the caller found it reading them
// (null: a pass of their own finds it).
Status check_boundary(const std::vector<BTree*>& octants, BTree& stored, MemoryBudget surface,
                      uint64_t held, size_t max_problems, const LeafSpan* span,
                      std::vector<std::string>* problems);

}  // namespace weaver
