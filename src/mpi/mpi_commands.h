// weaver-mpi's commands: each runs on every rank of MPI_COMM_WORLD and
// returns the process exit status, the same on every rank.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "balance/balance.h"
#include "boundary/boundary.h"
#include "extract/extract.h"
#include "mpi/comm.h"

namespace weaver::mpi {

int construct(const Comm& comm, int argc, char** argv);
int extract(const Comm& comm, int argc, char** argv);
int balance(const Comm& comm, int argc, char** argv);
int mesh(const Comm& comm, int argc, char** argv);
int boundary(const Comm& comm, int argc, char** argv);
int export_parts(const Comm& comm, int argc, char** argv);
// The stages on an open command line's options (weaver-mpi mesh runs all three).
// With options.staged_octants (every rank's copy of what rank 0 staged on
// held, its writer), balance stages its table there in their place (and
// every rank gets its shards in *staged), and extract commits the node table
// there, so that the octants and nodes go live in one manifest.
int run_balance(const Comm& comm, const std::string& dir, const BalanceOptions& options,
                Database* held = nullptr, std::vector<ShardEntry>* staged = nullptr);
int run_extract(const Comm& comm, const std::string& dir, const ExtractOptions& options,
                Database* held = nullptr);
// The boundary table, committed on its own; on_held (the same on every
// rank): on rank 0's writer held (weaver-mpi mesh's, after extract).
int run_boundary(const Comm& comm, const std::string& dir, const BoundaryOptions& options,
                 Database* held = nullptr, bool on_held = false);

// What weaver-mpi mesh's construct leaves for its extract: rank 0's writer,
// with the octant table's shards staged, and (on every rank) those shards.
struct StagedOctants {
  std::unique_ptr<Database> db;
  std::vector<ShardEntry> shards;
};
// weaver-mpi construct; with staged, the shards are staged there rather
// than committed.
int run_construct(const Comm& comm, int argc, char** argv, StagedOctants* staged);

}  // namespace weaver::mpi
