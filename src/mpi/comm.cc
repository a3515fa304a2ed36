#include "mpi/comm.h"

#include <mpi.h>

namespace weaver::mpi {

Comm::Comm(int* argc, char*** argv) {
  MPI_Init(argc, argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

Comm::~Comm() { MPI_Finalize(); }

uint64_t Comm::broadcast(uint64_t v) const {
  MPI_Bcast(&v, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
  return v;
}

std::string Comm::broadcast(const std::string& s) const {
  uint64_t n = broadcast(uint64_t{s.size()});
  std::string out = rank_ == 0 ? s : std::string(n, '\0');
  MPI_Bcast(out.data(), static_cast<int>(n), MPI_CHAR, 0, MPI_COMM_WORLD);
  return out;
}

std::vector<std::string> Comm::gather(const std::string& mine) const {
  int n = static_cast<int>(mine.size());
  std::vector<int> sizes(rank_ == 0 ? size_ : 0), at(rank_ == 0 ? size_ : 0);
  MPI_Gather(&n, 1, MPI_INT, sizes.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string all;
  if (rank_ == 0) {
    int total = 0;
    for (int r = 0; r < size_; ++r) at[r] = total, total += sizes[r];
    all.resize(total);
  }
  MPI_Gatherv(mine.data(), n, MPI_CHAR, all.data(), sizes.data(), at.data(), MPI_CHAR, 0,
              MPI_COMM_WORLD);
  std::vector<std::string> out;
  for (int r = 0; rank_ == 0 && r < size_; ++r) out.push_back(all.substr(at[r], sizes[r]));
  return out;
}

bool Comm::all(bool mine) const {
  int v = mine ? 1 : 0, out = 0;
  MPI_Allreduce(&v, &out, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
  return out != 0;
}

}  // namespace weaver::mpi
