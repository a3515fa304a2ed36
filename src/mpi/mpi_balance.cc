// weaver-mpi balance: the 2:1 balanced refinement of DB's octant table, one
// shard a rank, in two message rounds (balance/balance_shard.h: each rank
// asks the others for the leaves in its leaves' insulation layers, then
// balances its own leaves with them), committed by rank 0, which holds the
// database's writer lock throughout.
#include <chrono>
#include <cstdio>
#include <sstream>

#include "balance/balance_shard.h"
#include "cli/cli.h"
#include "mpi/mpi_commands.h"
#include "mpi/shards.h"

namespace weaver::mpi {
namespace {

constexpr char kUsage[] =
    "usage: mpirun -np N weaver-mpi balance DB [--memory BYTES] [--threads N]\n"
    "\n"
    "The minimal face+edge 2:1 balanced refinement of DB's octant table (sharded\n"
    "or not), as 'weaver balance' writes it, as a table of one shard a rank.\n"
    "Rank r takes the r-th of N equal runs of leaves.  In two message rounds,\n"
    "whatever the levels, each rank asks the others for their leaves that meet\n"
    "its leaves' insulation layers (the 3 x 3 x 3 block of octants of a leaf's\n"
    "size around it, as p4est's balance) and gets them; then it balances its\n"
    "own leaves with those by the serial out-of-core balance, in a scratch\n"
    "database in DB, and keeps its own.  DB must be on a file system every rank\n"
    "sees.  'weaver compact DB' joins the shards into the serial balance's file.\n"
    "\n"
    "  --memory BYTES   each rank's budget (default 256M), cut as weaver balance's\n"
    "  --threads N      threads a rank (default 1)\n";

}  // namespace

int balance(const Comm& comm, int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"memory", "threads"}, {"quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return cli::usage_error("balance", st.message(), kUsage);
  if (args.positional.size() != 1) return cli::usage_error("balance", "expected one DB", kUsage);
  BalanceOptions o;
  st = cli::memory_option(args, &o.memory);
  if (st.ok()) st = cli::threads_option(args, 1, &o.threads);
  if (!st.ok()) return cli::usage_error("balance", st.message(), kUsage);
  return run_balance(comm, args.positional[0], o);
}

int run_balance(const Comm& comm, const std::string& dir, const BalanceOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<Database> db;
  uint64_t number = 0;
  if (!open_writer(comm, "balance", dir, &db, &number)) return 1;
  uint64_t messages = 0;
  const RankExchange exchange = [&](const std::vector<std::string>& blobs,
                                    std::vector<std::string>* received) {
    *received = comm.exchange(blobs);
    for (int r = 0; r < comm.size(); ++r) messages += r != comm.rank() && !blobs[r].empty();
    return Status::Ok();
  };
  BalanceShardResult r;
  ShardEntry entry;
  const Status st =
      balance_shard(dir, o, comm.rank(), comm.size(),
                    shard_file_name(kOctantTable, number, comm.rank()), exchange, &r, &entry);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ostringstream line;
  line.precision(3);
  line << std::fixed << "rank " << comm.rank() << "  " << r.balance.output_leaves << " leaves in "
       << secs << "s, layer of " << r.layer_received << " leaves for " << r.queries_sent
       << " queries, sent " << r.bytes_sent << " B in " << messages << " messages, received "
       << r.bytes_received << " B, wrote " << r.table_bytes << " B, peak RSS " << peak_rss_bytes()
       << " B";
  return finish_stage(comm, db.get(), "balance", kOctantTable, entry,
                      st.ok() ? "" : cli::error_text(st), line.str(), r.balance.output_leaves,
                      "leaves", t0);
}

}  // namespace weaver::mpi
