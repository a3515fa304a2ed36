// The few collective operations weaver-mpi's stages need, over
// MPI_COMM_WORLD.  The only file besides comm.cc that sees MPI is none: the
// stages (construct_shard, commit_shards) know nothing of MPI, so the
// default build and libweaver never link it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace weaver::mpi {

class Comm {
 public:
  // MPI_Init; run without mpirun, one rank (MPI's singleton start).
  Comm(int* argc, char*** argv);
  ~Comm();  // MPI_Finalize
  Comm(const Comm&) = delete;
  Comm& operator=(const Comm&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  // Rank 0's value, on every rank.
  uint64_t broadcast(uint64_t v) const;
  std::string broadcast(const std::string& s) const;
  // Every rank's string, in rank order, on rank 0 (empty elsewhere).
  std::vector<std::string> gather(const std::string& mine) const;
  // Whether every rank's flag is true, on every rank.
  bool all(bool mine) const;
  // All to all: blobs[r] goes to rank r; returns what each rank sent here,
  // in rank order.  Of any size: sent in rounds of at most 1 GB / ranks a
  // peer, as MPI's int counts and offsets need.  (gather and the string
  // broadcast carry status lines and command lines: one message each.)
  std::vector<std::string> exchange(const std::vector<std::string>& blobs) const;

 private:
  int rank_ = 0, size_ = 1;
};

}  // namespace weaver::mpi
