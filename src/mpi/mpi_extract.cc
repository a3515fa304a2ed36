// weaver-mpi extract: the node table of a balanced octree, one shard a rank
// (extract/extract.h, extract_shard: equal counts of leaves a rank, node
// ownership by key, the corners crossing into later ranks exchanged once),
// committed by rank 0, which holds the database's writer lock throughout.
#include <chrono>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "cli/cli.h"
#include "db/node_table.h"
#include "extract/extract.h"
#include "mpi/mpi_commands.h"
#include "mpi/shards.h"
#include "util/varint.h"

namespace weaver::mpi {
namespace {

constexpr char kUsage[] =
    "usage: mpirun -np N weaver-mpi extract DB [--memory BYTES] [--threads N] [--plain]\n"
    "\n"
    "The mesh nodes of the balanced octree in DB's octant table (sharded or not),\n"
    "as 'weaver extract --algorithm sort' finds them, written as a node table of\n"
    "one shard a rank: rank r takes the r-th of N equal runs of leaves and owns\n"
    "the node keys from its first leaf's Morton code to the next rank's.  The\n"
    "corners its leaves give to later ranks that those ranks cannot find from\n"
    "their own leaves (dangling ones and those on the domain's far faces) are\n"
    "sent to them once, before any bucket runs; leaves of other ranks that a\n"
    "node's classification needs are\n"
    "read from DB, which every rank must see (a shared file system).  'weaver\n"
    "compact DB' joins the shards into the file the serial extract writes.\n"
    "\n"
    "  --memory BYTES   each rank's budget (default 256M), cut as weaver extract's\n"
    "  --threads N      worker threads a rank (default 1)\n"
    "  --plain          plain leaf pages instead of packed ones\n";

// Each rank's records for every rank, as bytes (keys as varint deltas:
// they come sorted, one a key; then the direction bits), and back.
std::string encode(const std::vector<SpillRecord>& records) {
  std::string out;
  uint64_t last = 0;
  for (const SpillRecord& r : records) {
    append_key_delta(out, &last, r.key);
    out.push_back(static_cast<char>(r.mask));
  }
  return out;
}

void decode(const std::string& bytes, std::vector<SpillRecord>* out) {
  size_t pos = 0;
  uint64_t last = 0;
  SpillRecord r;
  while (pos < bytes.size() && read_key_delta(bytes, &pos, &last, &r.key) && pos < bytes.size()) {
    r.mask = static_cast<uint8_t>(bytes[pos++]);
    out->push_back(r);
  }
}

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

int run_extract(const Comm& comm, const std::string& dir, const ExtractOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<Database> db;
  uint64_t number = 0;
  if (!open_writer(comm, "extract", dir, &db, &number)) return 1;
  uint64_t sent = 0, received = 0, messages = 0;
  const CornerExchange exchange = [&](std::vector<std::vector<SpillRecord>>& outgoing,
                                      std::vector<SpillRecord>* incoming) {
    std::vector<std::string> blobs;
    for (int r = 0; r < comm.size(); ++r) {
      blobs.push_back(r == comm.rank() ? std::string() : encode(outgoing[r]));
      sent += blobs.back().size();
      messages += !blobs.back().empty();
    }
    incoming->clear();
    for (const std::string& b : comm.exchange(blobs)) {
      received += b.size();
      decode(b, incoming);
    }
    return Status::Ok();
  };
  ExtractResult r;
  ShardEntry entry;
  const Status st =
      extract_shard(dir, o, comm.rank(), comm.size(),
                    shard_file_name(kNodeTable, number, comm.rank()), exchange, &r, &entry);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ostringstream line;
  line.precision(3);
  line << std::fixed << "rank " << comm.rank() << "  " << r.nodes << " nodes of " << r.elements
       << " elements in " << secs << "s, corners sent " << sent << " B in " << messages
       << " messages, received " << received << " B, wrote " << r.node_table_bytes
       << " B, peak RSS " << peak_rss_bytes() << " B";
  return finish_stage(comm, db.get(), "extract", kNodeTable, entry,
                      st.ok() ? "" : cli::error_text(st), line.str(), r.nodes, "nodes", t0);
}

}  // namespace weaver::mpi
