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

std::vector<std::string> Comm::exchange(const std::vector<std::string>& blobs) const {
  std::vector<int> send_n(size_), send_at(size_), recv_n(size_), recv_at(size_);
  std::string send;
  for (int r = 0; r < size_; ++r) {
    send_at[r] = static_cast<int>(send.size());
    send_n[r] = static_cast<int>(blobs[r].size());
    send += blobs[r];
  }
  MPI_Alltoall(send_n.data(), 1, MPI_INT, recv_n.data(), 1, MPI_INT, MPI_COMM_WORLD);
  int total = 0;
  for (int r = 0; r < size_; ++r) recv_at[r] = total, total += recv_n[r];
  std::string recv(total, '\0');
  MPI_Alltoallv(send.data(), send_n.data(), send_at.data(), MPI_CHAR, recv.data(), recv_n.data(),
                recv_at.data(), MPI_CHAR, MPI_COMM_WORLD);
  std::vector<std::string> out;
  for (int r = 0; r < size_; ++r) out.push_back(recv.substr(recv_at[r], recv_n[r]));
  return out;
}

bool Comm::all(bool mine) const {
  int v = mine ? 1 : 0, out = 0;
  MPI_Allreduce(&v, &out, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
  return out != 0;
}

}  // namespace weaver::mpi
