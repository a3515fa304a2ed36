// The bare LSM store killed at every durable step (storage/crash_point.h) of
// a workload of puts, erases, flushes, merges, compactions and commits: the
// reopened store holds exactly the state of one of its commits (never a mix),
// its leftovers are gone, and it goes on taking writes.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <random>
#include <vector>

#include "storage/crash_point.h"
#include "storage/lsm.h"
#include "test_util.h"

namespace weaver {
namespace {

namespace fs = std::filesystem;
using State = std::map<uint64_t, uint64_t>;

LsmOptions options() {
  LsmOptions o;
  std::string error;
  o.table.schema = *RecordSchema::parse("v:u64", &error);
  o.table.page_size = 256;
  o.table.packed = true;
  o.memtable_bytes = 2 << 10;  // flushes and tiered merges all the time
  o.run_pool_bytes = 8 << 10;
  return o;
}

// The workload: rounds of random puts and erases, each ending in a commit
// (every third a full compaction).  `on_commit` sees the state committed.
Status workload(const std::string& dir, const std::function<void(const State&)>& on_commit) {
  std::unique_ptr<LsmTree> t;
  WEAVER_RETURN_IF_ERROR(LsmTree::create(dir, options(), &t));
  std::mt19937_64 rng(7);
  State model;
  for (int round = 0; round < 4; ++round) {
    for (int i = 0; i < 200; ++i) {
      const uint64_t k = rng() % 2000, v = rng();
      if (rng() % 5 == 0 && model.count(k)) {
        WEAVER_RETURN_IF_ERROR(t->erase(k));
        model.erase(k);
      } else {
        WEAVER_RETURN_IF_ERROR(t->put(k, reinterpret_cast<const std::byte*>(&v), nullptr));
        model[k] = v;
      }
    }
    if (round % 3 == 2) WEAVER_RETURN_IF_ERROR(t->compact());
    WEAVER_RETURN_IF_ERROR(t->commit());
    on_commit(model);
  }
  return Status::Ok();
}

// What a reopened store holds; empty optional if it does not open.
std::optional<State> read_back(const std::string& dir) {
  std::unique_ptr<LsmTree> t;
  if (!LsmTree::open(dir, options(), &t).ok()) return std::nullopt;
  std::unique_ptr<Cursor> c;
  if (!t->seek(0, &c).ok()) return std::nullopt;
  State s;
  while (c->valid()) {
    uint64_t v = 0;
    std::memcpy(&v, c->payload(), 8);
    s[c->key()] = v;
    if (!c->next().ok()) return std::nullopt;
  }
  return s;
}

TEST(LsmCrash, EveryStepLeavesACommittedState) {
  testing::TempDir tmp;
  std::vector<State> commits = {State{}};
  const std::string ref = tmp.file("ref");
  crash_point::arm(0);
  ASSERT_OK(workload(ref, [&](const State& s) { commits.push_back(s); }));
  const uint64_t steps = crash_point::steps_taken();
  crash_point::disarm();
  ASSERT_GT(steps, 100u);
  const uint64_t points = std::min<uint64_t>(steps, testing::scaled(120, 15));
  int recovered = 0, fresh = 0;
  uint64_t fired = 0;
  for (uint64_t p = 0; p < points; ++p) {
    const uint64_t at = 1 + p * steps / points;
    const std::string dir = tmp.file("crash");
    fs::remove_all(dir);
    const pid_t pid = fork();
    if (pid == 0) {
      crash_point::arm(at);
      (void)workload(dir, [](const State&) {});
      _exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    // The workload runs to its end only if the point never fired.
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 137)
        << "step " << at << ": the kill point did not fire (status " << status << ")";
    ++fired;
    if (!fs::exists(dir + "/LSM")) {  // died before the first commit
      ++fresh;
      continue;
    }
    const std::optional<State> back = read_back(dir);
    ASSERT_TRUE(back.has_value()) << "step " << at << ": the store does not reopen";
    ASSERT_NE(std::find(commits.begin(), commits.end(), *back), commits.end())
        << "step " << at << ": not the state of any commit";
    // Leftovers gone, and it takes writes again.
    std::unique_ptr<LsmTree> t;
    ASSERT_OK(LsmTree::open(dir, options(), &t));
    for (const auto& e : fs::directory_iterator(dir)) {
      ASSERT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
    }
    const uint64_t v = 42;
    ASSERT_OK(t->put(5000, reinterpret_cast<const std::byte*>(&v), nullptr));
    ASSERT_OK(t->commit());
    ++recovered;
  }
  crash_point::disarm();
  std::printf(
      "LSM kill points: %llu fired of %llu steps; %d reopened to a committed state, %d before "
      "any\n",
      (unsigned long long)fired, (unsigned long long)steps, recovered, fresh);
  EXPECT_EQ(fired, points);
  EXPECT_GT(recovered, 0);
}

}  // namespace
}  // namespace weaver
