// weaver-mpi extract: the node table of a balanced octree, one shard a rank
// (extract/extract.h, extract_shard: equal counts of leaves a rank, node
// ownership by key, a ghost layer of the leaves around its nodes exchanged
// once), committed by rank 0, which holds the database's writer lock
// throughout.
#include <chrono>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "cli/cli.h"
#include "db/node_table.h"
#include "extract/extract.h"
#include "mpi/mpi_commands.h"
#include "mpi/shards.h"

namespace weaver::mpi {
namespace {

constexpr char kUsage[] =
    "usage: mpirun -np N weaver-mpi extract DB [--memory BYTES] [--threads N] [--plain]\n"
    "\n"
    "The mesh nodes of the balanced octree in DB's octant table (sharded or not),\n"
    "as 'weaver extract --algorithm sort' finds them, written as a node table of\n"
    "one shard a rank: rank r takes the r-th of N equal runs of leaves and owns\n"
    "the node keys from its first leaf's Morton code to the next rank's.  Before\n"
    "any bucket runs, each rank sends once, to each later rank, its leaves whose\n"
    "far faces reach into that rank's keys (the ghost layer); of the leaves a\n"
    "rank then reads from DB only its own run.  'weaver compact DB' joins the\n"
    "shards into the file the serial extract writes.\n"
    "\n"
    "  --memory BYTES   each rank's budget (default 256M), cut as weaver extract's\n"
    "  --threads N      worker threads a rank (default 1)\n"
    "  --plain          plain leaf pages instead of packed ones\n";

}  // namespace

int extract(const Comm& comm, int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"memory", "threads"}, {"plain", "quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return cli::usage_error("extract", st.message(), kUsage);
  if (args.positional.size() != 1) return cli::usage_error("extract", "expected one DB", kUsage);
  ExtractOptions o;
  o.packed = !args.flags.count("plain");
  st = cli::memory_option(args, &o.memory);
  if (st.ok()) st = cli::threads_option(args, 1, &o.threads);
  if (!st.ok()) return cli::usage_error("extract", st.message(), kUsage);
  return run_extract(comm, args.positional[0], o);
}

int run_extract(const Comm& comm, const std::string& dir, const ExtractOptions& o, Database* held) {
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<Database> own;
  Database* db = nullptr;
  uint64_t number = 0;
  if (!stage_writer(comm, "extract", dir, held, !o.staged_octants.empty(), &own, &db, &number)) {
    return 1;
  }
  uint64_t messages = 0;
  const RankExchange exchange = [&](const std::vector<std::string>& blobs,
                                    std::vector<std::string>* received) {
    *received = comm.exchange(blobs);
    for (int r = 0; r < comm.size(); ++r) messages += r != comm.rank() && !blobs[r].empty();
    return Status::Ok();
  };
  ExtractResult r;
  ShardEntry entry;
  ShardExchangeCounts x;
  const Status st =
      extract_shard(dir, o, comm.rank(), comm.size(),
                    shard_file_name(kNodeTable, number, comm.rank()), exchange, &r, &entry, &x);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ostringstream line;
  line.precision(3);
  line << std::fixed << "rank " << comm.rank() << "  " << r.nodes << " nodes of " << r.elements
       << " elements in " << secs << "s, ghost layer of " << x.ghosts_received << " leaves (gave "
       << x.ghosts_sent << "), sent " << x.bytes_sent << " B in " << messages
       << " messages, received " << x.bytes_received << " B, wrote " << r.node_table_bytes
       << " B, peak RSS " << peak_rss_bytes() << " B";
  // With o.stage (weaver-mpi mesh), the node shards go live with the
  // boundary's commit.
  std::vector<ShardEntry> staged;
  return finish_stage(comm, db, "extract", kNodeTable, entry, st.ok() ? "" : cli::error_text(st),
                      line.str(), r.nodes, "nodes", t0, o.stage ? &staged : nullptr);
}

}  // namespace weaver::mpi
