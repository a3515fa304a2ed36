// Sharded tables in a database (db/database.h): written as weaver-mpi's
// ranks write them (construct_shard per rank, commit_shards by the writer),
// read by every stage through the same BTree interface, and joined by
// compact into the very file the single-process run writes.  Each run is
// checked against the single-process database of the same octree, byte for
// byte: the tables a stage writes from sharded input, and the compacted ones.
#include <gtest/gtest.h>

#include <algorithm>
#include <condition_variable>
#include <filesystem>
#include <map>
#include <mutex>
#include <thread>

#include "balance/balance.h"
#include "balance/balance_shard.h"
#include "construct/construct.h"
#include "db/compact.h"
#include "db/database.h"
#include "db/octant_table.h"
#include "export/export.h"
#include "extract/extract.h"
#include "gen/octree_gen.h"
#include "import/import.h"
#include "import/octant_text.h"
#include "sample_octrees.h"
#include "test_util.h"
#include "verify/verify.h"

namespace weaver {
namespace {

using testing::random_octree;
using testing::slurp;
using testing::TempDir;
using testing::two_family_octree;

std::string table_file(const std::string& db, const std::string& table) {
  std::unique_ptr<Database> d;
  EXPECT_OK(Database::open(db, Database::Mode::kRead, false, &d));
  return d->table_path(table);
}

// Constructs db as `shards` ranks would, one construct_shard a rank, in turn.
void construct_sharded(const std::string& db, ConstructOptions o, int shards) {
  std::unique_ptr<Database> writer;
  ASSERT_OK(Database::open(db, Database::Mode::kWrite, true, &writer));
  const uint64_t number = writer->reserve_file_number();
  std::vector<ShardEntry> entries;
  for (int s = 0; s < shards; ++s) {
    o.shard = s;
    o.shards = shards;
    ConstructPlan plan;
    ConstructResult r;
    ShardEntry e;
    ASSERT_OK(construct_shard(db, o, shard_file_name(kOctantTable, number, s), &plan, &r, &e));
    if (e.records > 0) entries.push_back(e);
  }
  ASSERT_OK(writer->commit_shards(kOctantTable, entries));
}

// Copies table `name` of src into dst as `shards` shards of about equal
// counts, each with its own level counts (an octant table) as construct_shard
// writes them.
void reshard(const std::string& src, const std::string& dst, const std::string& name, int shards) {
  std::unique_ptr<Database> from, to;
  ASSERT_OK(Database::open(src, Database::Mode::kRead, false, &from));
  ASSERT_OK(Database::open(dst, Database::Mode::kWrite, true, &to));
  std::unique_ptr<BTree> t;
  ASSERT_OK(from->open_table(name, 4 << 20, &t));
  const uint64_t number = to->reserve_file_number();
  BTreeCursor c;
  ASSERT_OK(t->seek_cursor(0, &c));
  std::vector<ShardEntry> entries;
  for (int s = 0; s < shards && c.valid(); ++s) {
    const uint64_t n = t->size() * (s + 1) / shards - t->size() * s / shards;
    ShardEntry e{shard_file_name(name, number, s)};
    std::unique_ptr<BTree> out;
    ASSERT_OK(create_shard_table(dst, e.file, t->options(), 1 << 20, &out));
    LevelCounts levels{};
    e.first_key = c.key();
    for (uint64_t i = 0; i < n && c.valid(); ++i) {
      ASSERT_OK(out->append(c.key(), c.payload()));
      if (t->options().key_kind == KeyKind::kOctant) ++levels[c.key() & 127];
      e.last_key = c.key();
      ASSERT_OK(c.next());
    }
    const std::string& meta = t->options().metadata;
    out->set_metadata(with_shard_place(
        t->options().key_kind == KeyKind::kOctant ? with_levels(meta, levels) : meta,
        ShardPlace{s, shards}));
    ASSERT_OK(out->commit());
    e.records = out->size();
    entries.push_back(e);
  }
  ASSERT_OK(to->commit_shards(name, entries));
}

void expect_verified(const std::string& db) {
  VerifyReport report;
  ASSERT_OK(verify_database(db, VerifyOptions{}, &report));
  EXPECT_TRUE(report.ok()) << db << ": " << report.problems.front();
}

ConstructOptions basin(double freq) {
  ConstructOptions o;
  o.model = "basin";
  o.freq = freq;
  o.domain_m = {100000, 75000, 37500};  // not a cube: 8 x 6 x 3 blocks
  o.threads = 2;
  return o;
}

TEST(ShardedDatabase, ConstructShardsCompactToTheSingleRunsTable) {
  TempDir dir;
  const ConstructOptions o = basin(testing::small_scale() ? 0.1 : 0.2);
  ConstructPlan plan;
  ConstructResult r;
  const std::string single = dir.file("single");
  ASSERT_OK(construct_octree(single, o, &plan, &r));
  const std::string want = slurp(table_file(single, kOctantTable));
  // More shards than the estimate has cells to cut at leaves some empty.
  for (int shards : {1, 2, 3, 4, 7}) {
    SCOPED_TRACE(shards);
    const std::string db = dir.file("sharded" + std::to_string(shards));
    construct_sharded(db, o, shards);
    std::unique_ptr<Database> d;
    ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &d));
    const std::vector<ShardEntry> entries = d->shards_of(kOctantTable);
    ASSERT_FALSE(entries.empty());
    if (shards > 1) {
      EXPECT_GT(entries.size(), 1u);
    }
    std::unique_ptr<BTree> t;
    ASSERT_OK(d->open_table(kOctantTable, 4 << 20, &t));
    EXPECT_EQ(t->size(), r.elements);
    d.reset();
    expect_verified(db);
    CompactResult cr;
    ASSERT_OK(compact_database(db, MemoryBudget(), &cr));
    ASSERT_EQ(cr.tables.size(), 1u);
    EXPECT_EQ(cr.tables[0].shards, entries.size());
    ASSERT_TRUE(slurp(table_file(db, kOctantTable)) == want);
    // The shard files are gone with the commit.
    for (const ShardEntry& e : entries) EXPECT_FALSE(std::filesystem::exists(db + "/" + e.file));
    ASSERT_OK(compact_database(db, MemoryBudget(), &cr));
    EXPECT_TRUE(cr.tables.empty());
  }
}

// Shards staged by a writer (weaver-mpi mesh's construct, on rank 0) are
// the table for that writer and for a reader told of them (the other
// ranks), while the manifest still names the old table; the writer's next
// commit makes them live, and a writer that closes without one deletes them
// and leaves the old state.
TEST(ShardedDatabase, StagedShardsGoLiveWithTheNextCommitOrNotAtAll) {
  TempDir dir;
  const ConstructOptions o = basin(0.1);
  const std::string db = dir.file("db");
  ConstructPlan plan;
  ConstructResult old_r;
  ASSERT_OK(construct_octree(db, basin(0.05), &plan, &old_r));
  const std::string old_manifest = slurp(db + "/MANIFEST");
  for (const bool commit : {false, true}) {
    SCOPED_TRACE(commit);
    std::unique_ptr<Database> writer;
    ASSERT_OK(Database::open(db, Database::Mode::kWrite, false, &writer));
    const uint64_t number = writer->reserve_file_number();
    std::vector<ShardEntry> entries;
    uint64_t leaves = 0;
    for (int s = 0; s < 3; ++s) {
      ConstructOptions part = o;
      part.shard = s;
      part.shards = 3;
      ConstructResult r;
      ShardEntry e;
      ASSERT_OK(construct_shard(db, part, shard_file_name(kOctantTable, number, s), &plan, &r, &e));
      if (e.records > 0) entries.push_back(e);
      leaves += r.elements;
    }
    ASSERT_OK(writer->stage_shards(kOctantTable, entries));
    std::unique_ptr<BTree> t;
    ASSERT_OK(writer->open_table(kOctantTable, 4 << 20, &t));
    EXPECT_EQ(t->size(), leaves);
    std::unique_ptr<Database> reader, other;
    ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &reader));
    ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &other));
    ASSERT_OK(reader->stage_shards(kOctantTable, entries));
    ASSERT_OK(reader->open_table(kOctantTable, 4 << 20, &t));
    EXPECT_EQ(t->size(), leaves);
    ASSERT_OK(other->open_table(kOctantTable, 4 << 20, &t));
    EXPECT_EQ(t->size(), old_r.elements);  // a reader not told sees the manifest's
    EXPECT_EQ(slurp(db + "/MANIFEST"), old_manifest);
    reader.reset();  // a reader deletes nothing
    for (const ShardEntry& e : entries) EXPECT_TRUE(std::filesystem::exists(db + "/" + e.file));
    if (commit) ASSERT_OK(writer->commit({}));
    writer.reset();
    for (const ShardEntry& e : entries) {
      EXPECT_EQ(std::filesystem::exists(db + "/" + e.file), commit) << e.file;
    }
    std::unique_ptr<Database> after;
    ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &after));
    ASSERT_OK(after->open_table(kOctantTable, 4 << 20, &t));
    EXPECT_EQ(t->size(), commit ? leaves : old_r.elements);
    if (!commit) {
      EXPECT_EQ(slurp(db + "/MANIFEST"), old_manifest);
    }
  }
}

// Every stage reads sharded tables as it reads one file: balance from sharded
// leaves, extract from sharded balanced leaves, verify and export over
// sharded octant and node tables, each writing what it writes from the
// single database.
TEST(ShardedDatabase, StagesReadShardedTablesAsOne) {
  TempDir dir;
  const std::string single = dir.file("single"), sharded = dir.file("sharded");
  ConstructPlan plan;
  ConstructResult r;
  const ConstructOptions o = basin(0.1);
  ASSERT_OK(construct_octree(single, o, &plan, &r));
  construct_sharded(sharded, o, 3);
  BalanceResult br;
  ASSERT_OK(balance_octree(single, BalanceOptions{}, &br));
  ASSERT_OK(balance_octree(sharded, BalanceOptions{}, &br));
  ASSERT_TRUE(slurp(table_file(sharded, kOctantTable)) == slurp(table_file(single, kOctantTable)));
  ExtractResult er;
  ASSERT_OK(extract_mesh(single, ExtractOptions{}, &er));
  for (int shards : {2, 5}) {
    SCOPED_TRACE(shards);
    const std::string db = dir.file("balanced" + std::to_string(shards));
    reshard(single, db, kOctantTable, shards);
    ASSERT_OK(extract_mesh(db, ExtractOptions{}, &er));
    ASSERT_TRUE(slurp(table_file(db, "nodes")) == slurp(table_file(single, "nodes")));
    // Both tables sharded: the mesh check and an export.
    const std::string both = dir.file("both" + std::to_string(shards));
    reshard(single, both, kOctantTable, shards);
    reshard(single, both, "nodes", shards + 1);
    expect_verified(both);
    for (const std::string& db_dir : {single, both}) {
      ExportOptions x;
      x.format = ExportFormat::kVtu;
      x.out = db_dir + ".vtu";
      ExportResult xr;
      ASSERT_OK(export_mesh(db_dir, x, &xr));
    }
    ASSERT_TRUE(slurp(both + ".vtu") == slurp(single + ".vtu"));
  }
}

// The ranks of a parallel stage as threads: in each round, each deposits
// what it sends to every rank, waits for all, and takes what the others sent
// it, in rank order (MPI_Alltoallv's contract, which weaver-mpi keeps).
template <class T>
class ThreadExchange {
 public:
  explicit ThreadExchange(int ranks) : boxes_(ranks, std::vector<T>(ranks)) {}
  std::vector<T> run(int rank, std::vector<T> out) {
    EXPECT_EQ(out.size(), boxes_.size()) << "rank " << rank << " must send to every rank";
    std::unique_lock<std::mutex> l(m_);
    const uint64_t round = round_;
    for (size_t to = 0; to < out.size(); ++to) boxes_[to][rank] = std::move(out[to]);
    if (++arrived_ == int(boxes_.size())) {
      arrived_ = 0;
      ready_ = std::move(boxes_);
      boxes_.assign(ready_.size(), std::vector<T>(ready_.size()));
      ++round_;
      all_.notify_all();
    } else {
      all_.wait(l, [&] { return round_ != round; });
    }
    return std::move(ready_[rank]);
  }

 private:
  std::mutex m_;
  std::condition_variable all_;
  std::vector<std::vector<T>> boxes_, ready_;  // [to][from]
  int arrived_ = 0;
  uint64_t round_ = 0;
};

// Extracts db on `ranks` threads as weaver-mpi's ranks do: each rank's
// status, and its shard in *entries.
std::vector<Status> extract_on_ranks(const std::string& db, int ranks, uint64_t number,
                                     std::vector<ShardEntry>* entries) {
  ThreadExchange<std::string> exchange(ranks);
  entries->assign(ranks, ShardEntry{});
  std::vector<Status> status(ranks);
  std::vector<std::thread> threads;
  for (int r = 0; r < ranks; ++r) {
    threads.emplace_back([&, r] {
      ExtractResult er;
      ExtractOptions o;
      o.bucket_leaves = 500;  // many buckets a rank
      o.memory = MemoryBudget(16 << 20);
      ShardExchangeCounts x;
      status[r] = extract_shard(
          db, o, r, ranks, shard_file_name("nodes", number, r),
          [&](const std::vector<std::string>& out, std::vector<std::string>* in) {
            *in = exchange.run(r, out);
            return Status::Ok();
          },
          &er, &(*entries)[r], &x);
    });
  }
  for (auto& t : threads) t.join();
  return status;
}

// Extracts db on `ranks` threads and commits the node shards.
void extract_sharded(const std::string& db, int ranks) {
  std::unique_ptr<Database> writer;
  ASSERT_OK(Database::open(db, Database::Mode::kWrite, false, &writer));
  std::vector<ShardEntry> entries;
  const std::vector<Status> status =
      extract_on_ranks(db, ranks, writer->reserve_file_number(), &entries);
  std::vector<ShardEntry> kept;
  for (int r = 0; r < ranks; ++r) {
    ASSERT_OK(status[r]);
    if (entries[r].records > 0) kept.push_back(entries[r]);
  }
  ASSERT_OK(writer->commit_shards("nodes", kept));
}

// A parallel extract writes, shard by shard, the serial run's node table:
// on the basin (sharded leaves or not) and on random octrees with holes and
// deep grading, with more ranks than some octrees have leaves.
TEST(ShardedDatabase, ExtractOnRanksCompactsToTheSerialNodeTable) {
  TempDir dir;
  std::vector<std::string> octrees;
  const std::string basin_db = dir.file("basin");
  ConstructPlan plan;
  ConstructResult r;
  ASSERT_OK(construct_octree(basin_db, basin(0.1), &plan, &r));
  octrees.push_back(basin_db);
  for (uint64_t seed : {5, 6}) {
    octrees.push_back(random_octree(dir, "random" + std::to_string(seed), seed, seed == 5 ? 12 : 7,
                                    seed == 6, testing::scaled(20000, 5000)));
  }
  octrees.push_back(two_family_octree(dir, "families"));
  for (const std::string& db : octrees) {
    BalanceResult br;
    ASSERT_OK(balance_octree(db, BalanceOptions{}, &br));
    ExtractResult er;
    const std::string serial = db + ".serial";
    std::filesystem::copy(db, serial);
    ASSERT_OK(extract_mesh(serial, ExtractOptions{}, &er));
    const std::string want = slurp(table_file(serial, "nodes"));
    for (int ranks : {1, 2, 3, 5, 8}) {
      SCOPED_TRACE(db + " on " + std::to_string(ranks) + " ranks");
      const std::string run = db + "." + std::to_string(ranks);
      std::filesystem::remove_all(run);
      if (db == basin_db && ranks == 3) {
        reshard(db, run, kOctantTable, 4);  // sharded leaves, cut elsewhere
      } else {
        std::filesystem::copy(db, run);
      }
      extract_sharded(run, ranks);
      expect_verified(run);
      CompactResult cr;
      ASSERT_OK(compact_database(run, MemoryBudget(), &cr));
      ASSERT_TRUE(slurp(table_file(run, "nodes")) == want);
    }
  }
}

// An octree that is not 2:1 balanced where earlier ranks' coarse leaves meet
// later ranks' fine ones (the root's last child cut two levels finer than
// its siblings): some rank refuses it, naming the unbalanced pair, as the
// serial extract does.  On 9 and 71 ranks the coarse children are all
// before the fine ones' ranks, which own the nodes between them and see
// the coarse leaves only in their ghost layers.
TEST(ShardedDatabase, ExtractOnRanksRefusesAnOctreeUnbalancedAcrossRanks) {
  TempDir dir;
  std::vector<Octant> octants;
  for (int k = 0; k < 8; ++k) {
    const Octant child = octant_child(octant_root(), k);
    if (k != 7) octants.push_back(child);
    for (int j = 0; k == 7 && j < 8; ++j) {
      for (int i = 0; i < 8; ++i) octants.push_back(octant_child(octant_child(child, j), i));
    }
  }
  const std::string db = testing::imported_octree(dir, "steep", octants);
  ExtractResult er;
  const Status serial = extract_mesh(db, ExtractOptions{}, &er);
  ASSERT_FALSE(serial.ok());
  EXPECT_NE(serial.message().find("not 2:1 balanced"), std::string::npos) << serial.message();
  for (int ranks : {2, 3, 5, 9, 71}) {
    SCOPED_TRACE(std::to_string(ranks) + " ranks");
    std::vector<ShardEntry> entries;
    int refused = 0;
    for (const Status& st : extract_on_ranks(db, ranks, 1000 + ranks, &entries)) {
      if (st.ok()) continue;
      EXPECT_NE(st.message().find("not 2:1 balanced"), std::string::npos) << st.message();
      ++refused;
    }
    EXPECT_GT(refused, 0);
  }
}

// Balances db on `ranks` threads as weaver-mpi's ranks do (in windows of
// at most window_leaves, or by the exchanges and the closure), and commits
// the octant shards.
void balance_sharded(const std::string& db, int ranks, bool windows = true,
                     uint64_t window_leaves = 0) {
  std::unique_ptr<Database> writer;
  ASSERT_OK(Database::open(db, Database::Mode::kWrite, false, &writer));
  const uint64_t number = writer->reserve_file_number();
  ThreadExchange<std::string> exchange(ranks);
  std::vector<ShardEntry> entries(ranks);
  std::vector<Status> status(ranks);
  std::vector<std::thread> threads;
  for (int r = 0; r < ranks; ++r) {
    threads.emplace_back([&, r] {
      BalanceShardResult br;
      BalanceOptions o;
      o.memory = MemoryBudget(16 << 20);
      o.algorithm =
          windows ? BalanceOptions::Algorithm::kWindows : BalanceOptions::Algorithm::kClosure;
      o.window_leaves = window_leaves;
      status[r] = balance_shard(
          db, o, r, ranks, shard_file_name(kOctantTable, number, r),
          [&](const std::vector<std::string>& out, std::vector<std::string>* in) {
            *in = exchange.run(r, out);
            return Status::Ok();
          },
          &br, &entries[r]);
    });
  }
  for (auto& t : threads) t.join();
  std::vector<ShardEntry> kept;
  for (int r = 0; r < ranks; ++r) {
    ASSERT_OK(status[r]);
    if (entries[r].records > 0) kept.push_back(entries[r]);
  }
  ASSERT_OK(writer->commit_shards(kOctantTable, kept));
}

// A parallel balance writes, shard by shard, the serial run's balanced
// table: on the basin (built sharded or not) and on random octrees with
// holes, deep grading and a non-cube domain, on up to more ranks than some
// stretches have leaves; each rank in windows (long or a few hundred
// leaves) or by the exchanges and the closure.
TEST(ShardedDatabase, BalanceOnRanksCompactsToTheSerialTable) {
  TempDir dir;
  std::vector<std::string> octrees;
  ConstructPlan plan;
  ConstructResult r;
  const std::string basin_db = dir.file("basin");
  ASSERT_OK(construct_octree(basin_db, basin(0.1), &plan, &r));
  octrees.push_back(basin_db);
  for (uint64_t seed : {7, 8, 9}) {
    octrees.push_back(random_octree(dir, "unbalanced" + std::to_string(seed), seed,
                                    seed == 8 ? 12 : 8, seed != 7, testing::scaled(20000, 4000)));
  }
  octrees.push_back(two_family_octree(dir, "families"));
  for (const std::string& db : octrees) {
    const std::string serial = db + ".serial";
    std::filesystem::copy(db, serial);
    BalanceResult br;
    ASSERT_OK(balance_octree(serial, BalanceOptions{}, &br));
    const std::string want = slurp(table_file(serial, kOctantTable));
    for (int ranks : {1, 2, 3, 4, 7, -2, -7}) {
      // Negative: as many ranks, the other way.
      const bool windows = ranks > 0;
      ranks = std::abs(ranks);
      SCOPED_TRACE(db + " on " + std::to_string(ranks) + " ranks" +
                   (windows ? ", windows" : ", closure"));
      const std::string run = db + ".b" + std::to_string(ranks) + (windows ? "w" : "c");
      std::filesystem::remove_all(run);
      if (db == basin_db && ranks == 3) {
        construct_sharded(run, basin(0.1), 2);  // sharded input, cut elsewhere
      } else {
        std::filesystem::copy(db, run);
      }
      balance_sharded(run, ranks, windows, ranks == 4 ? 300 : 0);
      std::unique_ptr<Database> d;
      ASSERT_OK(Database::open(run, Database::Mode::kRead, false, &d));
      ASSERT_EQ(d->shards_of(kOctantTable).empty(), false);
      d.reset();
      expect_verified(run);
      CompactResult cr;
      ASSERT_OK(compact_database(run, MemoryBudget(), &cr));
      ASSERT_TRUE(slurp(table_file(run, kOctantTable)) == want);
    }
  }
}

// The files of db's tables, by name.
std::map<std::string, std::string> table_bytes(const std::string& db) {
  std::map<std::string, std::string> out;
  CompactResult cr;
  EXPECT_OK(compact_database(db, MemoryBudget(), &cr));
  for (const char* t : {kOctantTable, "nodes"}) out[t] = slurp(table_file(db, t));
  return out;
}

bool mentions(const std::vector<std::string>& lines, const std::string& what) {
  return std::any_of(lines.begin(), lines.end(),
                     [&](const std::string& l) { return l.find(what) != std::string::npos; });
}

// A sharded database that lost its manifest gets its tables back from the
// shard files, whole sets only: each shard names its place among its
// table's (empty ranks write none, and are not counted), so a set with a
// file missing, first, in the middle or last, is set aside, never used.
TEST(ShardedDatabase, RecoverRebuildsShardedTablesFromWholeSetsOnly) {
  TempDir dir;
  const std::string basin_db = dir.file("basin");
  construct_sharded(basin_db, basin(0.1), 3);
  balance_sharded(basin_db, 4);
  extract_sharded(basin_db, 3);
  const std::string families = two_family_octree(dir, "families");
  balance_sharded(families, 7);  // ranks left empty between ranks with leaves
  extract_sharded(families, 8);
  std::filesystem::copy(basin_db, basin_db + ".sharded");
  for (const std::string& db : {basin_db, families}) {
    SCOPED_TRACE(db);
    std::filesystem::copy(db, db + ".saved");
    const std::map<std::string, std::string> want = table_bytes(db + ".saved");
    std::filesystem::remove(db + "/MANIFEST");
    RecoverReport report;
    ASSERT_OK(Database::recover(db, &report));
    EXPECT_TRUE(report.set_aside.empty()) << report.set_aside.front();
    ASSERT_EQ(report.tables.size(), 2u);
    EXPECT_TRUE(mentions(report.tables, "shards)")) << report.tables.front();
    expect_verified(db);
    EXPECT_TRUE(table_bytes(db) == want);
  }
  // Sets that lost a file.
  std::unique_ptr<Database> d;
  ASSERT_OK(Database::open(basin_db + ".sharded", Database::Mode::kRead, false, &d));
  const std::vector<ShardEntry> octants = d->shards_of(kOctantTable);
  const std::vector<ShardEntry> nodes = d->shards_of("nodes");
  d.reset();
  ASSERT_EQ(octants.size(), 4u);
  for (size_t lost = 0; lost < octants.size(); ++lost) {
    SCOPED_TRACE("octant shard " + std::to_string(lost) + " lost");
    const std::string db = dir.file("lost" + std::to_string(lost));
    std::filesystem::copy(basin_db + ".sharded", db);
    std::filesystem::remove(db + "/MANIFEST");
    std::filesystem::remove(db + "/" + octants[lost].file);
    RecoverReport report;
    ASSERT_OK(Database::recover(db, &report));
    EXPECT_TRUE(report.tables.empty()) << report.tables.front();  // the nodes derive from them
    EXPECT_TRUE(mentions(report.set_aside, "missing")) << report.set_aside.front();
    for (const ShardEntry& e : octants) {
      if (e.file == octants[lost].file) continue;
      EXPECT_TRUE(std::filesystem::exists(db + "/" + e.file + ".unused")) << e.file;
    }
    for (const ShardEntry& e : nodes) {
      EXPECT_TRUE(std::filesystem::exists(db + "/" + e.file + ".unused")) << e.file;
    }
  }
}

TEST(ShardedDatabase, ManifestShardsOutOfOrderOrMiscountedAreCorruption) {
  TempDir dir;
  const std::string db = dir.file("db");
  construct_sharded(db, basin(0.1), 2);
  const std::string manifest = slurp(db + "/MANIFEST");
  std::unique_ptr<Database> d;
  ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &d));
  std::vector<ShardEntry> e = d->shards_of(kOctantTable);
  ASSERT_EQ(e.size(), 2u);
  d.reset();
  // A miscounted shard: the manifest's count against the file's.
  {
    std::unique_ptr<Database> w;
    ASSERT_OK(Database::open(db, Database::Mode::kWrite, false, &w));
    e[1].records += 1;
    ASSERT_OK(w->commit_shards(kOctantTable, e));
  }
  ASSERT_OK(Database::open(db, Database::Mode::kRead, false, &d));
  std::unique_ptr<BTree> t;
  const Status st = d->open_table(kOctantTable, 1 << 20, &t);
  ASSERT_FALSE(st.ok());
  EXPECT_NE(st.message().find(e[1].file), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("MANIFEST says"), std::string::npos) << st.message();
  d.reset();
  // Shards listed out of order.
  {
    std::unique_ptr<Database> w;
    ASSERT_OK(Database::open(db, Database::Mode::kWrite, false, &w));
    e[1].records -= 1;
    std::swap(e[0], e[1]);
    ASSERT_OK(w->commit_shards(kOctantTable, e));
  }
  const Status open = Database::open(db, Database::Mode::kRead, false, &d);
  ASSERT_FALSE(open.ok());
  EXPECT_NE(open.message().find("out of order"), std::string::npos) << open.message();
}

}  // namespace
}  // namespace weaver
