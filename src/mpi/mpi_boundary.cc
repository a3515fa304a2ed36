// weaver-mpi boundary (and the last stage of weaver-mpi mesh): the boundary
// table (boundary/boundary.h, boundary_shard), one shard a rank: rank r
// takes the r-th of N equal runs of elements, and the box the leaves span,
// the least edge / vp and the counts are gathered from every rank.  The
// shards compact to the table `weaver boundary` writes.
#include <chrono>
#include <cstdio>
#include <sstream>

#include "boundary/boundary.h"
#include "cli/cli.h"
#include "db/boundary_table.h"
#include "mpi/mpi_commands.h"
#include "mpi/shards.h"

namespace weaver::mpi {
namespace {

constexpr char kUsage[] =
    "usage: mpirun -np N weaver-mpi boundary DB [--memory BYTES] [--plain]\n"
    "\n"
    "The boundary table of the mesh in DB (sharded or not), as 'weaver boundary'\n"
    "writes it: every element face, or quarter of a face, with no element across\n"
    "it, tagged free surface or domain side.  Rank r derives the records of the\n"
    "r-th of N equal runs of elements; the box the leaves span and the counts\n"
    "are gathered from every rank, so 'weaver compact DB' joins the shards into\n"
    "the file the serial command writes.  weaver-mpi mesh runs it last.\n"
    "\n"
    "  --memory BYTES   each rank's budget (default 256M)\n"
    "  --plain          plain leaf pages instead of packed ones\n";

}  // namespace

int boundary(const Comm& comm, int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"memory"}, {"plain", "quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return cli::usage_error("boundary", st.message(), kUsage);
  if (args.positional.size() != 1) return cli::usage_error("boundary", "expected one DB", kUsage);
  BoundaryOptions o;
  o.packed = !args.flags.count("plain");
  st = cli::memory_option(args, &o.memory);
  if (!st.ok()) return cli::usage_error("boundary", st.message(), kUsage);
  return run_boundary(comm, args.positional[0], o);
}

int run_boundary(const Comm& comm, const std::string& dir, const BoundaryOptions& o, Database* held,
                 bool on_held) {
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<Database> own;
  Database* db = nullptr;
  uint64_t number = 0;
  if (!stage_writer(comm, "boundary", dir, held, on_held, &own, &db, &number)) return 1;
  const RankAllGather all_gather = [&comm](const std::string& mine, std::vector<std::string>* all) {
    *all = comm.exchange(std::vector<std::string>(comm.size(), mine));
    return Status::Ok();
  };
  BoundaryResult r;
  ShardEntry entry;
  const Status st =
      boundary_shard(dir, o, comm.rank(), comm.size(),
                     shard_file_name(kBoundaryTable, number, comm.rank()), all_gather, &r, &entry);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ostringstream line;
  line.precision(3);
  line << std::fixed << "rank " << comm.rank() << "  " << entry.records << " faces of "
       << r.elements << " elements in " << secs << "s (" << r.asked
       << " asked their neighbours), wrote " << r.table_bytes << " B, peak RSS " << peak_rss_bytes()
       << " B";
  return finish_stage(comm, db, "boundary", kBoundaryTable, entry,
                      st.ok() ? "" : cli::error_text(st), line.str(), entry.records, "faces", t0);
}

}  // namespace weaver::mpi
