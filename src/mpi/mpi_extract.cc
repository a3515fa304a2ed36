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

namespace weaver::mpi {
namespace {

constexpr char kUsage[] =
    "usage: mpirun -np N weaver-mpi extract DB [--memory BYTES] [--threads N] [--plain]\n"
    "\n"
    "The mesh nodes of the balanced octree in DB's octant table (sharded or not),\n"
    "as 'weaver extract --algorithm sort' finds them, written as a node table of\n"
    "one shard a rank: rank r takes the r-th of N equal runs of leaves and owns\n"
    "the node keys from its first leaf's Morton code to the next rank's.  The\n"
    "corners its leaves give to later ranks are sent to them once, before any\n"
    "bucket runs; leaves of other ranks that a node's classification needs are\n"
    "read from DB, which every rank must see (a shared file system).  'weaver\n"
    "compact DB' joins the shards into the file the serial extract writes.\n"
    "\n"
    "  --memory BYTES   each rank's budget (default 256M), cut as weaver extract's\n"
    "  --threads N      worker threads a rank (default 1)\n"
    "  --plain          plain leaf pages instead of packed ones\n";

// Each rank's records for every rank, as bytes, and back.
std::string encode(const std::vector<SpillRecord>& records) {
  std::string out(records.size() * 9, '\0');
  for (size_t i = 0; i < records.size(); ++i) {
    std::memcpy(&out[9 * i], &records[i].key, 8);
    out[9 * i + 8] = static_cast<char>(records[i].mask);
  }
  return out;
}

void decode(const std::string& bytes, std::vector<SpillRecord>* out) {
  for (size_t i = 0; i + 9 <= bytes.size(); i += 9) {
    SpillRecord r;
    std::memcpy(&r.key, &bytes[i], 8);
    r.mask = static_cast<uint8_t>(bytes[i + 8]);
    out->push_back(r);
  }
}

struct Traffic {
  uint64_t sent = 0, received = 0;  // bytes of corners
};

std::string outcome(const ShardEntry& e, const ExtractResult& r, const Traffic& t, double secs,
                    const std::string& error) {
  std::ostringstream s;
  s.precision(17);
  s << e.file << ' ' << e.records << ' ' << e.first_key << ' ' << e.last_key << ' ' << r.elements
    << ' ' << r.nodes << ' ' << r.anchored << ' ' << r.edge << ' ' << r.face << ' '
    << r.node_table_bytes << ' ' << t.sent << ' ' << t.received << ' ' << secs << '\n'
    << error;
  return s.str();
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
  const std::string dir = args.positional[0];
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<Database> db;
  uint64_t number = 0;
  std::string failed;
  if (comm.rank() == 0) {
    st = Database::open(dir, Database::Mode::kWrite, false, &db);
    if (st.ok()) number = db->reserve_file_number();
    if (!st.ok()) failed = cli::error_text(st);
  }
  if (!comm.all(failed.empty())) {
    if (comm.rank() == 0) std::fprintf(stderr, "weaver-mpi extract: %s\n", failed.c_str());
    return 1;
  }
  number = comm.broadcast(number);
  Traffic traffic;
  const CornerExchange exchange = [&](std::vector<std::vector<SpillRecord>>& outgoing,
                                      std::vector<SpillRecord>* incoming) {
    std::vector<std::string> blobs;
    for (int r = 0; r < comm.size(); ++r) {
      blobs.push_back(r == comm.rank() ? std::string() : encode(outgoing[r]));
      traffic.sent += blobs.back().size();
    }
    incoming->clear();
    for (const std::string& b : comm.exchange(blobs)) {
      traffic.received += b.size();
      decode(b, incoming);
    }
    return Status::Ok();
  };
  ExtractResult r;
  ShardEntry entry;
  st = extract_shard(dir, o, comm.rank(), comm.size(),
                     shard_file_name(kNodeTable, number, comm.rank()), exchange, &r, &entry);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::vector<std::string> texts =
      comm.gather(outcome(entry, r, traffic, secs, st.ok() ? "" : cli::error_text(st)));
  int code = 0;
  if (comm.rank() == 0) {
    std::vector<ShardEntry> shards;
    std::vector<std::string> errors;
    ExtractResult sum;
    for (int rank = 0; rank < comm.size(); ++rank) {
      std::istringstream s(texts[rank]);
      ShardEntry e;
      ExtractResult x;
      Traffic t;
      double rank_secs = 0;
      s >> e.file >> e.records >> e.first_key >> e.last_key >> x.elements >> x.nodes >>
          x.anchored >> x.edge >> x.face >> x.node_table_bytes >> t.sent >> t.received >> rank_secs;
      s.ignore(1);
      std::string error;
      std::getline(s, error, '\0');
      shards.push_back(e);
      errors.push_back(error);
      sum.elements += x.elements, sum.nodes += x.nodes, sum.anchored += x.anchored;
      sum.edge += x.edge, sum.face += x.face;
      std::printf(
          "rank %-4d %llu elements, %llu nodes in %.2fs, corners sent %llu B, received "
          "%llu B, wrote %llu B\n",
          rank, (unsigned long long)x.elements, (unsigned long long)x.nodes, rank_secs,
          (unsigned long long)t.sent, (unsigned long long)t.received,
          (unsigned long long)x.node_table_bytes);
    }
    code = commit_or_fail(*db, "extract", kNodeTable, shards, errors);
    const double all = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (code == 0) {
      std::printf(
          "extracted %llu nodes (%llu anchored, %llu edge-dangling, %llu face-dangling) from "
          "%llu elements in %.2fs on %d ranks\n",
          (unsigned long long)sum.nodes, (unsigned long long)sum.anchored,
          (unsigned long long)sum.edge, (unsigned long long)sum.face,
          (unsigned long long)sum.elements, all, comm.size());
    }
  }
  return static_cast<int>(comm.broadcast(uint64_t(code)));
}

}  // namespace weaver::mpi
