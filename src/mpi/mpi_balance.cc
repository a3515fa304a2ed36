// weaver-mpi balance: the 2:1 balanced refinement of DB's octant table, one
// shard a rank (balance/balance_shard.h: each rank balances its own run of
// leaves in windows against their insulation layers, read from the table,
// or asks the others for those layers in two message rounds), committed by
// rank 0, which holds the database's writer lock throughout.
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
    "usage: mpirun -np N weaver-mpi balance DB [--algorithm auto|windows|closure]\n"
    "                                        [--memory BYTES] [--threads N]\n"
    "\n"
    "The minimal face+edge 2:1 balanced refinement of DB's octant table (sharded\n"
    "or not), as 'weaver balance' writes it, as a table of one shard a rank.\n"
    "Rank r takes the r-th of N equal runs of leaves.  A leaf's refinement\n"
    "depends only on the leaves that meet its insulation layer (the 3 x 3 x 3\n"
    "block of octants of its size around it, as in p4est's balance).\n"
    "  --algorithm windows  each rank balances its run in windows, each against\n"
    "                   the leaves of its layer read from DB's table: no message\n"
    "                   but one byte a rank (did every window fit?)\n"
    "  --algorithm closure  in two message rounds, whatever the levels, each rank\n"
    "                   asks the others for their leaves in its leaves' layers\n"
    "                   and gets them, then balances its own with those by the\n"
    "                   closure, in a scratch database in DB\n"
    "  --algorithm auto  windows (default), all ranks taking the closure's way\n"
    "                   when a window on any rank does not fit in the memory or\n"
    "                   its layer outweighs it\n"
    "DB must be on a file system every rank sees.  'weaver compact DB' joins the\n"
    "shards into the serial balance's file.\n"
    "\n"
    "  --memory BYTES   each rank's budget (default 256M), cut as weaver balance's\n"
    "  --threads N      threads a rank (default 1)\n"
    "  --model db:PATH  the model database the octants were built from, where it\n"
    "                   is not DB's own (as weaver balance's)\n";

}  // namespace

int balance(const Comm& comm, int argc, char** argv) {
  ParsedArgs args;
  Status st =
      parse_args(argc, argv, 2, {"algorithm", "model", "memory", "threads"}, {"quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return cli::usage_error("balance", st.message(), kUsage);
  if (args.positional.size() != 1) return cli::usage_error("balance", "expected one DB", kUsage);
  BalanceOptions o;
  st = cli::memory_option(args, &o.memory);
  if (st.ok()) st = cli::threads_option(args, 1, &o.threads);
  if (st.ok()) st = cli::balance_algorithm_option(args, &o.algorithm);
  if (st.ok()) st = cli::balance_model_option(args, &o.model_dirs);
  if (!st.ok()) return cli::usage_error("balance", st.message(), kUsage);
  return run_balance(comm, args.positional[0], o);
}

int run_balance(const Comm& comm, const std::string& dir, const BalanceOptions& o, Database* held,
                std::vector<ShardEntry>* staged) {
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<Database> own;
  Database* db = nullptr;
  uint64_t number = 0;
  if (!stage_writer(comm, "balance", dir, held, !o.staged_octants.empty(), &own, &db, &number)) {
    return 1;
  }
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
  return finish_stage(comm, db, "balance", kOctantTable, entry, st.ok() ? "" : cli::error_text(st),
                      line.str(), r.balance.output_leaves, "leaves", t0,
                      o.staged_octants.empty() ? nullptr : staged);
}

}  // namespace weaver::mpi
