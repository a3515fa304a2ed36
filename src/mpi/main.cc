// weaver-mpi: weaver's stages on the ranks of an MPI job (mpirun -np N
// weaver-mpi COMMAND ...), each rank writing a shard of the table
// (db/database.h: sharded tables); run without mpirun it is one rank and
// writes what the serial weaver does, as one shard.  Every rank must be given
// the same arguments.  Only rank 0 prints; a rank's error reaches it and is
// printed naming the rank.
#include <cstdio>
#include <cstring>
#include <string>

#include "mpi/comm.h"
#include "mpi/mpi_commands.h"

namespace {

constexpr char kUsage[] =
    "usage: mpirun -np N weaver-mpi <command> [args]\n"
    "\n"
    "Commands (each takes --help; their options are weaver's):\n"
    "  construct DB      the octree of a velocity model, one shard a rank\n"
    "  balance DB        2:1 balance the octant table in two message rounds\n"
    "  extract DB        the mesh nodes of a balanced octree, one shard a rank\n"
    "  boundary DB       the boundary faces of a mesh, one shard a rank\n"
    "  mesh DB ...       construct, balance, extract and boundary (construct's\n"
    "                    options)\n"
    "  export DB ...     raw --parts N or pvtu, one part a rank (N = ranks)\n"
    "\n"
    "The other commands (query, export of one file, verify, stat, ...) are\n"
    "the serial weaver's, and read a sharded database as any other; 'weaver\n"
    "compact DB' joins its shards into the files the serial run writes.\n";

// Every rank's command line must be rank 0's: options that differ would cut
// the domain differently on different ranks.
std::string joined(int argc, char** argv) {
  std::string s;
  for (int i = 0; i < argc; ++i) s += std::string(argv[i]) + '\0';
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  weaver::mpi::Comm comm(&argc, &argv);
  const std::string mine = joined(argc - 1, argv + 1);
  if (!comm.all(comm.broadcast(mine) == mine)) {
    if (comm.rank() == 0) {
      std::fprintf(stderr, "weaver-mpi: the ranks were started with different arguments\n");
    }
    return 2;
  }
  // One voice: rank 0's.  Every other rank's error reaches it by message.
  if (comm.rank() != 0) {
    if (!std::freopen("/dev/null", "w", stdout) || !std::freopen("/dev/null", "w", stderr)) {
      return 1;
    }
  }
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h")) {
    std::fputs(kUsage, argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  const std::string cmd = argv[1];
  if (cmd == "construct") return weaver::mpi::construct(comm, argc, argv);
  if (cmd == "extract") return weaver::mpi::extract(comm, argc, argv);
  if (cmd == "balance") return weaver::mpi::balance(comm, argc, argv);
  if (cmd == "mesh") return weaver::mpi::mesh(comm, argc, argv);
  if (cmd == "boundary") return weaver::mpi::boundary(comm, argc, argv);
  if (cmd == "export") return weaver::mpi::export_parts(comm, argc, argv);
  std::fprintf(stderr, "weaver-mpi: unknown command '%s'\n\n%s", cmd.c_str(), kUsage);
  return 2;
}
