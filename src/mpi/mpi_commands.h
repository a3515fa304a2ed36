// weaver-mpi's commands: each runs on every rank of MPI_COMM_WORLD and
// returns the process exit status, the same on every rank.
#pragma once

#include <string>

#include "balance/balance.h"
#include "extract/extract.h"
#include "mpi/comm.h"

namespace weaver::mpi {

int construct(const Comm& comm, int argc, char** argv);
int extract(const Comm& comm, int argc, char** argv);
int balance(const Comm& comm, int argc, char** argv);
int mesh(const Comm& comm, int argc, char** argv);
int export_parts(const Comm& comm, int argc, char** argv);
// The stages on an open command line's options (weaver-mpi mesh runs all three).
int run_balance(const Comm& comm, const std::string& dir, const BalanceOptions& options);
int run_extract(const Comm& comm, const std::string& dir, const ExtractOptions& options);

}  // namespace weaver::mpi
