// Crash safety: every writer killed at many points leaves a database that
// opens, verifies, and holds exactly the state before or after the writer.
//
// Two kinds of kill point:
//  - a power cut at the N-th durable step of the writer (WEAVER_CRASH_AT=N,
//    storage/crash_point.h): bytes written since the file's last sync read
//    back as zeros, then the process dies;
//  - SIGKILL from the parent after a random delay within the writer's run.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <thread>

#include "db/database.h"
#include "import/octant_text.h"
#include "test_octrees.h"
#include "test_util.h"
#include "verify/verify.h"

namespace weaver {
namespace {

namespace fs = std::filesystem;

// What a database holds: per table, its record count and a hash of every key
// and payload, in order.
using Fingerprint = std::map<std::string, std::pair<uint64_t, uint64_t>>;

Fingerprint fingerprint(const std::string& dir) {
  Fingerprint f;
  std::unique_ptr<Database> db;
  if (!Database::open(dir, Database::Mode::kRead, false, &db).ok()) return f;  // no database yet
  for (const std::string& name : db->table_names()) {
    std::unique_ptr<BTree> t;
    EXPECT_OK(db->open_table(name, 1 << 20, &t));
    if (!t) continue;
    BTreeCursor c;
    EXPECT_OK(t->seek_cursor(0, &c));
    uint64_t h = 1469598103934665603ull;
    while (c.valid()) {
      h = (h ^ c.key()) * 1099511628211ull;
      for (uint32_t i = 0; i < t->payload_size(); ++i) {
        h = (h ^ static_cast<uint8_t>(c.payload()[i])) * 1099511628211ull;
      }
      EXPECT_OK(c.next());
    }
    f[name] = {t->size(), h};
  }
  return f;
}

// An I/O fault to inject instead of a crash: the step and the errno name.
struct Fault {
  uint64_t at = 0;  // 0: none
  const char* errno_name = "EIO";
  std::string stderr_file;  // where the writer's stderr goes ("": /dev/null)
};

// Runs the weaver binary; crash_at > 0 arms the crash point, kill_after_us
// >= 0 sends SIGKILL after that delay, fault.at > 0 fails that step.
// Returns the wait status.
int run_writer(const std::vector<std::string>& args, uint64_t crash_at, int64_t kill_after_us,
               const Fault& fault = {}) {
  const pid_t pid = fork();
  if (pid == 0) {
    if (crash_at > 0) setenv("WEAVER_CRASH_AT", std::to_string(crash_at).c_str(), 1);
    if (fault.at > 0) {
      setenv("WEAVER_FAIL_AT", std::to_string(fault.at).c_str(), 1);
      setenv("WEAVER_FAIL_ERRNO", fault.errno_name, 1);
    }
    const int null = ::open("/dev/null", O_WRONLY);
    const int err = fault.stderr_file.empty()
                        ? null
                        : ::open(fault.stderr_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(null, 1), dup2(err, 2);
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  if (kill_after_us >= 0) {
    std::this_thread::sleep_for(std::chrono::microseconds(kill_after_us));
    kill(pid, SIGKILL);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return status;
}

// How many durable steps the writer takes, from a counting run.
uint64_t count_steps(const std::vector<std::string>& args) {
  std::string cmd = "WEAVER_CRASH_AT=0";
  for (const std::string& a : args) cmd += " " + a;
  cmd += " 2>&1 >/dev/null | grep 'crash steps'";
  FILE* p = popen(cmd.c_str(), "r");
  unsigned long long n = 0;
  if (p != nullptr) {
    if (std::fscanf(p, "crash steps: %llu", &n) != 1) n = 0;
    pclose(p);
  }
  return n;
}

struct Writer {
  std::string name;
  std::vector<std::string> args;  // "{db}" stands for the database directory
};

class CrashTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // Inputs: an unbalanced random octree, and a second one to import over it.
    GenOptions g;
    g.seed = 21;
    g.blocks[0] = 2, g.blocks[1] = 1, g.blocks[2] = 1;
    g.block_level = 1;
    g.leaves = 3000;
    g.max_level = 7;
    std::vector<Octant> a, b;
    ASSERT_OK(generate_octree(g, &a));
    g.seed = 22;
    ASSERT_OK(generate_octree(g, &b));
    text_a_ = dir_.file("a.txt");
    text_b_ = dir_.file("b.txt");
    // A ground for the carved mesh: a ridge across the 100 km box, 0 to 3 km.
    dem_ = dir_.file("ridge.asc");
    std::ofstream dem(dem_);
    dem << "ncols 11\nnrows 11\nxllcenter 0\nyllcenter 0\ncellsize 10000\n";
    for (int r = 10; r >= 0; --r) {
      for (int c = 0; c <= 10; ++c) dem << 300 * (5 - std::abs(c - 5)) << " ";
      dem << "\n";
    }
    ASSERT_OK(write_octant_text(text_a_, a, ""));
    std::shuffle(b.begin(), b.end(), std::mt19937_64(3));  // out of order: the sort spills
    ASSERT_OK(write_octant_text(text_b_, b, ""));
  }

  std::vector<std::string> with_db(const Writer& w, const std::string& db) const {
    std::vector<std::string> out = {WEAVER_BINARY};
    for (const std::string& a : w.args) out.push_back(a == "{db}" ? db : a);
    return out;
  }

  // Builds the state before the writer with the given preparation commands.
  void prepare(const std::string& db, const std::vector<std::vector<std::string>>& steps) {
    fs::remove_all(db);
    for (const auto& s : steps) {
      std::vector<std::string> args = {WEAVER_BINARY};
      for (const std::string& a : s) args.push_back(a == "{db}" ? db : a);
      ASSERT_EQ(run_writer(args, 0, -1), 0) << s[0];
    }
  }

  // One kill point: from a copy of the old state, run and crash, then check.
  void check_one(const Writer& w, const std::string& old_db, const Fingerprint& before,
                 const Fingerprint& after, uint64_t crash_at, int64_t kill_after_us,
                 Fault fault = {}) {
    const std::string db = dir_.file("crash.db");
    fs::remove_all(db);
    if (fs::exists(old_db)) fs::copy(old_db, db, fs::copy_options::recursive);
    if (fault.at > 0) fault.stderr_file = dir_.file("fault.err");
    const int status = run_writer(with_db(w, db), crash_at, kill_after_us, fault);
    const std::string where =
        w.name + (fault.at
                      ? " failing step " + std::to_string(fault.at) + " with " + fault.errno_name
                  : crash_at ? " at step " + std::to_string(crash_at)
                             : " killed after " + std::to_string(kill_after_us) + " us");
    if (fault.at > 0) {
      ASSERT_NO_FATAL_FAILURE(check_fault_report(fault, status, where));
    }
    // A kill point armed at a step the writer takes must fire: the
    // simulator's death is exit status 137.  A timed kill fires unless the
    // writer finished first.
    if (crash_at > 0) {
      ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 137)
          << where << ": the kill point did not fire (status " << status << ")";
      ++fired_;
    }
    if (kill_after_us >= 0 && WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) ++fired_;
    if (fs::exists(db)) {  // the next writer's open removes leftovers, and says so
      auto files = [&] {
        size_t n = 0;
        for (const auto& e : fs::directory_iterator(db)) {
          n += e.path().filename() != "LOCK" && e.path().filename() != "MANIFEST";
        }
        return n;
      };
      const size_t files_before = files();
      std::unique_ptr<Database> d;
      ASSERT_OK(Database::open(db, Database::Mode::kWrite, true, &d));  // as import would
      const size_t files_after = files();
      ASSERT_EQ(files_before - files_after, d->cleaned_leftovers().size()) << where;
      for (const auto& e : fs::directory_iterator(db)) {
        const std::string f = e.path().filename().string();
        bool live = f == "MANIFEST" || f == "LOCK";
        for (const std::string& t : d->table_names())
          live = live || d->table_path(t) == e.path().string();
        ASSERT_TRUE(live) << where << ": leftover " << f << " survived the open";
      }
    }
    const Fingerprint now = fingerprint(db);
    ASSERT_TRUE(now == before || now == after) << where << ": neither the old nor the new state";
    if (!now.empty()) {
      VerifyReport r;
      VerifyOptions o;
      o.memory = MemoryBudget(4 << 20);
      ASSERT_OK(verify_database(db, o, &r));
      ASSERT_TRUE(r.ok()) << where << ": " << r.problems[0];
    }
    ++(now == after ? new_states_ : old_states_);
  }

  // A failed step: exit status 1 and one line naming the I/O error, unless
  // the step was one the writer may retry or ignore (then it succeeds).
  void check_fault_report(const Fault& fault, int status, const std::string& where) {
    std::ifstream in(fault.stderr_file);
    std::string err((std::istreambuf_iterator<char>(in)), {});
    ASSERT_TRUE(WIFEXITED(status)) << where << ": died";
    if (WEXITSTATUS(status) == 0) {
      ++faults_absorbed_;
      return;
    }
    ASSERT_EQ(WEXITSTATUS(status), 1) << where << ": " << err;
    ASSERT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << where << ": " << err;
    const std::string want =
        std::string(fault.errno_name) == "ENOSPC" ? "No space left" : "Input/output error";
    ASSERT_NE(err.find(want), std::string::npos) << where << ": " << err;
    ++faults_reported_;
    ++reported_by_[writer_];
  }

  // Kills the writer at every durable step (or `steps` of them, spread
  // evenly) and at `kills` random moments of its run; with `faults`, also
  // fails each of those steps with EIO and ENOSPC instead.
  void torture(const Writer& w, const std::vector<std::vector<std::string>>& setup, uint64_t steps,
               int kills, bool faults = false) {
    writer_ = w.name;
    reported_by_[writer_] += 0;  // every writer tortured has a count, if only 0
    const std::string old_db = dir_.file("old.db"), new_db = dir_.file("new.db");
    ASSERT_NO_FATAL_FAILURE(prepare(old_db, setup));
    const Fingerprint before = fingerprint(old_db);
    fs::remove_all(new_db);
    if (fs::exists(old_db)) fs::copy(old_db, new_db, fs::copy_options::recursive);
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_EQ(run_writer(with_db(w, new_db), 0, -1), 0) << w.name;
    const auto run_us =
        std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - t0)
            .count();
    const Fingerprint after = fingerprint(new_db);
    ASSERT_NE(before, after) << w.name << " changed nothing";
    const std::string count_db = new_db + ".count";
    fs::remove_all(count_db);
    if (fs::exists(old_db)) fs::copy(old_db, count_db, fs::copy_options::recursive);
    const uint64_t n = count_steps(with_db(w, count_db));
    ASSERT_GT(n, 0u) << w.name;
    const uint64_t points = std::min(n, steps);
    for (uint64_t i = 0; i < points; ++i) {
      if (faults) {
        for (const char* e : {"EIO", "ENOSPC"}) {
          ASSERT_NO_FATAL_FAILURE(
              check_one(w, old_db, before, after, 0, -1, {1 + i * n / points, e, ""}));
        }
        continue;
      }
      ASSERT_NO_FATAL_FAILURE(check_one(w, old_db, before, after, 1 + i * n / points, -1));
      ++points_;
    }
    std::mt19937_64 rng(w.name.size());
    for (int k = 0; k < kills; ++k) {
      ASSERT_NO_FATAL_FAILURE(
          check_one(w, old_db, before, after, 0, rng() % (run_us * 13 / 10 + 1)));
      ++points_;
    }
  }

  testing::TempDir dir_;
  std::string text_a_, text_b_, dem_;
  int points_ = 0, fired_ = 0, old_states_ = 0, new_states_ = 0;
  int faults_reported_ = 0, faults_absorbed_ = 0;
  std::string writer_;                      // the writer tortured now
  std::map<std::string, int> reported_by_;  // faults each writer reported

  // Every writer of the database, from its state before (setup commands).
  void each_writer(
      const std::function<void(const Writer&, const std::vector<std::vector<std::string>>&)>& f) {
    const std::vector<std::string> import_a = {"import", "{db}",     "--octants",
                                               text_a_,  "--memory", "1M"};
    const std::vector<std::string> import_b = {"import", "{db}",     "--octants",
                                               text_b_,  "--memory", "1M"};
    const std::vector<std::string> balance = {"balance", "{db}", "--memory", "1M"};
    const std::vector<std::string> extract = {"extract", "{db}", "--memory", "1M"};
    f({"import over a mesh", import_b}, {import_a, balance, extract});
    f({"import into a new database", import_b}, {});
    f({"construct", {"construct", "{db}", "--model", "basin", "--freq", "0.08", "--memory", "1M"}},
      {import_a});
    f({"balance", balance}, {import_a});
    f({"mesh over a mesh",
       {"mesh", "{db}", "--model", "basin", "--freq", "0.08", "--memory", "1M", "--quiet"}},
      {import_a, balance, extract});
    f({"mesh with a ground over a mesh",
       {"mesh", "{db}", "--model", "basin", "--freq", "0.08", "--surface", "asc:" + dem_,
        "--memory", "1M", "--quiet"}},
      {import_a, balance, extract});
    f({"boundary", {"boundary", "{db}", "--memory", "1M", "--quiet"}},
      {import_a, balance, extract});
    f({"extract (sort)", extract}, {import_a, balance});
    f({"extract (search, lsm)",
       {"extract", "{db}", "--algorithm", "search", "--store", "lsm", "--memory", "1M"}},
      {import_a, balance});
  }
};

// I/O errors (EIO, a full disk) at every durable step of every writer: the
// writer says so in one line and exits 1, the database holds the old state
// (or the new one, when only the final directory sync failed) and verifies.
TEST_F(CrashTest, IoErrorsAtEveryStepLeaveTheOldState) {
  const uint64_t steps = testing::scaled(60, 8);
  each_writer([&](const Writer& w, const std::vector<std::vector<std::string>>& setup) {
    torture(w, setup, steps, 0, true);
  });
  std::printf("injected faults: %d reported, %d absorbed; states: %d old, %d new\n",
              faults_reported_, faults_absorbed_, old_states_, new_states_);
  EXPECT_GT(faults_reported_, 0);
  EXPECT_GT(old_states_, 0);
  // Each writer failed, and said so, at least once: one that ignored the
  // injected faults (every step absorbed) would pass the totals above.
  EXPECT_EQ(reported_by_.size(), 9u);
  for (const auto& [name, n] : reported_by_) EXPECT_GT(n, 0) << name << " reported no fault";
}

TEST_F(CrashTest, EveryWriterLeavesTheOldOrTheNewState) {
  const uint64_t steps = testing::scaled(200, 25);
  const int kills = static_cast<int>(testing::scaled(200, 15));
  const std::vector<std::string> import_a = {"import", "{db}", "--octants", "", "--memory", "1M"};
  auto import_of = [&](const std::string& text) {
    std::vector<std::string> v = import_a;
    v[3] = text;
    return v;
  };
  const std::vector<std::string> balance = {"balance", "{db}", "--memory", "1M"};
  torture({"import over a table", import_of(text_b_)}, {import_of(text_a_)}, steps, kills);
  torture({"import into a new database", import_of(text_b_)}, {}, steps, kills);
  torture(
      {"construct", {"construct", "{db}", "--model", "basin", "--freq", "0.08", "--memory", "1M"}},
      {import_of(text_a_)}, steps, kills);
  torture({"balance", balance}, {import_of(text_a_)}, steps, kills);
  // A re-mesh: construct stages its table, extract commits both at once.
  torture({"mesh over a mesh",
           {"mesh", "{db}", "--model", "basin", "--freq", "0.08", "--memory", "1M", "--quiet"}},
          {import_of(text_a_), balance, {"extract", "{db}", "--memory", "1M"}}, steps, kills);
  torture({"mesh with a ground over a mesh",
           {"mesh", "{db}", "--model", "basin", "--freq", "0.08", "--surface", "asc:" + dem_,
            "--memory", "1M", "--quiet"}},
          {import_of(text_a_), balance, {"extract", "{db}", "--memory", "1M"}}, steps, kills);
  torture({"extract (sort)", {"extract", "{db}", "--memory", "1M"}}, {import_of(text_a_), balance},
          steps, kills);
  torture({"extract (search)", {"extract", "{db}", "--algorithm", "search", "--memory", "1M"}},
          {import_of(text_a_), balance}, steps, kills);
  // The LSM flushes, merges, compacts and commits its run list inside.
  torture({"extract (search, lsm)",
           {"extract", "{db}", "--algorithm", "search", "--store", "lsm", "--memory", "1M"}},
          {import_of(text_a_), balance}, steps, kills);
  std::printf("kill points: %d fired of %d armed (old state after %d, new state after %d)\n",
              fired_, points_, old_states_, new_states_);
  EXPECT_GE(fired_, static_cast<int>(testing::scaled(1000, 150)));
  EXPECT_GT(old_states_, 0);
  EXPECT_GT(new_states_, 0);
}

// Readers open a snapshot: while writers of every kind (import, balance,
// extract, construct) keep committing, every reader sees one whole committed
// state (both tables of the same commit), never an error.
TEST_F(CrashTest, ReadersSeeWholeStatesWhileEveryWriterCommits) {
  const std::vector<std::vector<std::string>> cycle = {
      {"import", "{db}", "--octants", text_a_},
      {"balance", "{db}"},
      {"extract", "{db}"},
      {"construct", "{db}", "--model", "basin", "--freq", "0.08"},
      {"balance", "{db}"},
      {"extract", "{db}", "--algorithm", "search"},
      {"import", "{db}", "--octants", text_b_},
      {"balance", "{db}"},
      {"extract", "{db}"},
  };
  auto run_step = [&](const std::string& db, size_t i) {
    std::vector<std::string> args = {WEAVER_BINARY};
    for (const std::string& a : cycle[i % cycle.size()]) args.push_back(a == "{db}" ? db : a);
    return run_writer(args, 0, -1);
  };
  // The states the cycle commits, from a dry run.
  const std::string dry = dir_.file("dry.db"), db = dir_.file("busy.db");
  std::vector<Fingerprint> states;
  for (size_t i = 0; i < cycle.size(); ++i) {
    ASSERT_EQ(run_step(dry, i), 0) << "step " << i << ": " << cycle[i][0];
    states.push_back(fingerprint(dry));
  }
  ASSERT_EQ(run_step(db, 0), 0);
  std::atomic<bool> stop{false};
  std::atomic<int> commits{0};
  std::thread writer([&] {
    for (size_t i = 1; !stop; ++i) {
      if (run_step(db, i) == 0) ++commits;
    }
  });
  int reads = 0;
  std::set<size_t> seen;
  const auto until =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(testing::scaled(3000, 1000));
  while (std::chrono::steady_clock::now() < until || commits < static_cast<int>(cycle.size())) {
    const Fingerprint f = fingerprint(db);
    const auto at = std::find(states.begin(), states.end(), f);
    ASSERT_NE(at, states.end()) << "read " << reads << " saw a mixed or failed state";
    seen.insert(at - states.begin());
    ++reads;
  }
  stop = true;
  writer.join();
  std::printf("%d reads across %d commits of %zu writers, %zu distinct states seen\n", reads,
              commits.load(), cycle.size(), seen.size());
  EXPECT_GE(seen.size(), 4u);
}

}  // namespace
}  // namespace weaver
