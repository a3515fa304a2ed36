// weaver-mpi's commands: each runs on every rank of MPI_COMM_WORLD and
// returns the process exit status, the same on every rank.
#pragma once

#include "mpi/comm.h"

namespace weaver::mpi {

int construct(const Comm& comm, int argc, char** argv);
int extract(const Comm& comm, int argc, char** argv);

}  // namespace weaver::mpi
