// weaver-mpi construct: every rank builds its part of the octree (the
// subtrees whose estimated share of the Z-order falls in its range:
// ConstructOptions::shard) into a shard file of its own; rank 0, holding the
// database's writer lock all along, commits the shards in one manifest once
// every rank has written and synced its file.  Any rank's failure fails the
// command, naming the rank, and leaves the old database.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "cli/cli.h"
#include "construct/construct.h"
#include "construct/estimate.h"
#include "db/database.h"
#include "mpi/mpi_commands.h"
#include "mpi/shards.h"

namespace weaver::mpi {
namespace {

// What one rank did: its shard, its figures, or its error ("" when ok).
struct Outcome {
  ShardEntry shard;
  ConstructResult result;
  double seconds = 0;
  uint64_t peak_rss = 0;
  std::string error;

  std::string encode() const {
    std::ostringstream s;
    s.precision(17);
    s << shard.records << ' ' << shard.first_key << ' ' << shard.last_key << ' ' << result.elements
      << ' ' << result.smallest_edge_m << ' ' << result.largest_edge_m << ' ' << result.worst_ppw
      << ' ' << result.table_bytes << ' ' << result.subtrees << ' ' << result.subtrees_over << ' '
      << result.descended << ' ' << result.neighbours << ' ' << seconds << ' ' << peak_rss << ' '
      << result.air << ' ' << result.cut << ' '
      << (std::isfinite(result.least_dt) ? result.least_dt : -1.0) << ' '  // no leaf: -1
      << result.least_dt_element;
    for (uint64_t l : result.levels) s << ' ' << l;
    s << ' ' << shard.file << '\n' << error;
    return s.str();
  }
  static Outcome decode(const std::string& text) {
    Outcome o;
    std::istringstream s(text);
    s >> o.shard.records >> o.shard.first_key >> o.shard.last_key >> o.result.elements >>
        o.result.smallest_edge_m >> o.result.largest_edge_m >> o.result.worst_ppw >>
        o.result.table_bytes >> o.result.subtrees >> o.result.subtrees_over >> o.result.descended >>
        o.result.neighbours >> o.seconds >> o.peak_rss >> o.result.air >> o.result.cut >>
        o.result.least_dt >> o.result.least_dt_element;
    if (o.result.least_dt < 0) o.result.least_dt = HUGE_VAL;
    for (uint64_t& l : o.result.levels) s >> l;
    s >> o.shard.file;
    s.ignore(1);
    std::getline(s, o.error, '\0');
    return o;
  }
};

// The ranks' figures as one run's: sums, and the extremes over ranks with leaves.
ConstructResult combine(const std::vector<Outcome>& all) {
  ConstructResult r;
  bool first = true;
  for (const Outcome& o : all) {
    const ConstructResult& x = o.result;
    r.table_bytes += x.table_bytes;
    r.subtrees += x.subtrees;
    r.subtrees_over += x.subtrees_over;
    r.descended += x.descended;
    r.neighbours += x.neighbours;
    r.air += x.air;
    r.cut += x.cut;
    for (size_t l = 0; l < r.levels.size(); ++l) r.levels[l] += x.levels[l];
    if (x.elements == 0) continue;
    // A rank's element ids start after the earlier ranks' elements.
    if (x.least_dt < r.least_dt)
      r.least_dt = x.least_dt, r.least_dt_element = r.elements + x.least_dt_element;
    r.smallest_edge_m = first ? x.smallest_edge_m : std::min(r.smallest_edge_m, x.smallest_edge_m);
    r.largest_edge_m = std::max(r.largest_edge_m, x.largest_edge_m);
    r.worst_ppw = first ? x.worst_ppw : std::min(r.worst_ppw, x.worst_ppw);
    r.elements += x.elements;
    first = false;
  }
  return r;
}

// Rank 0: imports a model file, plans, opens the database for writing and
// reserves the shards' file number.  The error, or "".
std::string prepare(const std::string& dir, ConstructOptions* o, ConstructPlan* plan,
                    std::unique_ptr<Database>* db, uint64_t* number) {
  Status st = cli::import_model_option(dir, o);
  if (st.ok()) st = plan_construct(*o, plan);
  if (!st.ok()) return cli::error_text(st);
  cli::print_construct_plan(*o, *plan, dir);
  st = check_construct_fits(*o, planned_estimate(*plan), dir);
  if (st.ok()) st = Database::open(dir, Database::Mode::kWrite, true, db);
  if (!st.ok()) return cli::error_text(st);
  *number = (*db)->reserve_file_number();
  return "";
}

// Rank 0: commits (or, for weaver-mpi mesh, stages: *staged) the shards,
// or removes them all after a rank's failure.
int finish(const Comm& comm, Database& db, const std::vector<Outcome>& all, double seconds,
           std::vector<ShardEntry>* staged) {
  std::vector<ShardEntry> shards;
  std::vector<std::string> errors;
  for (const Outcome& o : all) shards.push_back(o.shard), errors.push_back(o.error);
  if (const int code = commit_or_fail(db, "construct", kOctantTable, shards, errors,
                                      staged != nullptr, staged)) {
    return code;
  }
  // Construct exchanges nothing: each rank builds its part from the model.
  for (int r = 0; r < comm.size(); ++r) {
    std::printf(
        "rank %d  %llu leaves in %.3fs, sent 0 B in 0 messages, received 0 B, wrote %llu B, "
        "peak RSS %llu B%s\n",
        r, static_cast<unsigned long long>(all[r].result.elements), all[r].seconds,
        static_cast<unsigned long long>(all[r].result.table_bytes),
        static_cast<unsigned long long>(all[r].peak_rss),
        all[r].shard.records ? "" : " (no shard)");
  }
  const ConstructResult r = combine(all);
  cli::print_construct_result(r, seconds);
  cli::print_construct_balance(r);
  std::printf("sharded    table octants in shards of %d ranks ('weaver compact' joins them)\n",
              comm.size());
  return 0;
}

}  // namespace

int construct(const Comm& comm, int argc, char** argv) {
  return run_construct(comm, argc, argv, nullptr);
}

int run_construct(const Comm& comm, int argc, char** argv, StagedOctants* staged) {
  std::string dir;
  ConstructOptions o;
  bool quiet = false;
  const int parsed = cli::parse_construct_command(argc, argv, &dir, &o, &quiet);
  if (parsed >= 0) return parsed;
  const auto t0 = std::chrono::steady_clock::now();
  std::unique_ptr<Database> db;
  ConstructPlan plan;
  uint64_t number = 0;
  const std::string failed = comm.rank() == 0 ? prepare(dir, &o, &plan, &db, &number) : "";
  if (comm.rank() == 0) std::fflush(stdout);
  if (!comm.all(failed.empty())) {
    if (comm.rank() == 0) std::fprintf(stderr, "weaver-mpi construct: %s\n", failed.c_str());
    return 1;
  }
  // The model as rank 0 resolved it (a model file imported into DB).
  o.model = comm.broadcast(o.model);
  number = comm.broadcast(number);
  o.shard = comm.rank();
  o.shards = comm.size();
  Outcome mine;
  const Status st = construct_shard(dir, o, shard_file_name(kOctantTable, number, comm.rank()),
                                    &plan, &mine.result, &mine.shard);
  mine.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!st.ok()) mine.error = cli::error_text(st);
  mine.peak_rss = peak_rss_bytes();
  const std::vector<std::string> texts = comm.gather(mine.encode());
  int code = 0;
  if (comm.rank() == 0) {
    std::vector<Outcome> all;
    for (const std::string& t : texts) all.push_back(Outcome::decode(t));
    code = finish(comm, *db, all,
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(),
                  staged != nullptr ? &staged->shards : nullptr);
  }
  code = static_cast<int>(comm.broadcast(uint64_t(code)));
  if (staged != nullptr && code == 0) {
    staged->shards = decode_shards(comm.broadcast(encode_shards(staged->shards)));
    staged->db = std::move(db);  // rank 0's writer: the shards stay staged on it
  }
  return code;
}

}  // namespace weaver::mpi
