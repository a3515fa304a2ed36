#include "mpi/comm.h"

#include <mpi.h>

#include <algorithm>
#include <cstdlib>

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

namespace {

// Bytes a rank sends any one peer in one round of exchange(): MPI counts and
// offsets are ints, so a round's whole buffer must stay under 2 GB however
// large the blobs.  WEAVER_MPI_ROUND_BYTES sets it lower (tests: many rounds).
uint64_t round_bytes(int ranks) {
  uint64_t per_peer = (uint64_t{1} << 30) / static_cast<uint64_t>(ranks);
  if (const char* env = std::getenv("WEAVER_MPI_ROUND_BYTES")) {
    per_peer = std::max<uint64_t>(1, std::min<uint64_t>(per_peer, std::strtoull(env, nullptr, 10)));
  }
  return per_peer;
}

}  // namespace

std::vector<std::string> Comm::exchange(const std::vector<std::string>& blobs) const {
  std::vector<uint64_t> send_len(size_), recv_len(size_);
  for (int r = 0; r < size_; ++r) send_len[r] = blobs[r].size();
  MPI_Alltoall(send_len.data(), 1, MPI_UINT64_T, recv_len.data(), 1, MPI_UINT64_T, MPI_COMM_WORLD);
  const uint64_t per_peer = round_bytes(size_);
  uint64_t longest = 0, rounds = 0;
  for (int r = 0; r < size_; ++r) longest = std::max({longest, send_len[r], recv_len[r]});
  uint64_t mine = (longest + per_peer - 1) / per_peer;
  MPI_Allreduce(&mine, &rounds, 1, MPI_UINT64_T, MPI_MAX, MPI_COMM_WORLD);
  std::vector<std::string> out(size_);
  for (int r = 0; r < size_; ++r) out[r].resize(recv_len[r]);
  std::vector<int> send_n(size_), send_at(size_), recv_n(size_), recv_at(size_);
  std::string send, recv;
  for (uint64_t k = 0; k < rounds; ++k) {
    const uint64_t from = k * per_peer;
    auto piece = [&](uint64_t len) { return from < len ? std::min(per_peer, len - from) : 0; };
    send.clear();
    int total = 0;
    for (int r = 0; r < size_; ++r) {
      send_at[r] = static_cast<int>(send.size());
      send_n[r] = static_cast<int>(piece(send_len[r]));
      send.append(blobs[r], from < send_len[r] ? from : 0, send_n[r]);
      recv_at[r] = total;
      recv_n[r] = static_cast<int>(piece(recv_len[r]));
      total += recv_n[r];
    }
    recv.resize(total);
    MPI_Alltoallv(send.data(), send_n.data(), send_at.data(), MPI_CHAR, recv.data(), recv_n.data(),
                  recv_at.data(), MPI_CHAR, MPI_COMM_WORLD);
    for (int r = 0; r < size_; ++r) {
      if (recv_n[r] > 0) out[r].replace(from, recv_n[r], recv, recv_at[r], recv_n[r]);
    }
  }
  return out;
}

bool Comm::all(bool mine) const {
  int v = mine ? 1 : 0, out = 0;
  MPI_Allreduce(&v, &out, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
  return out != 0;
}

}  // namespace weaver::mpi
