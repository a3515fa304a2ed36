// Stages stay within their memory budget plus a small constant, whatever
// the mesh size: a mesh whose working set would be ~48 MB is extracted with a
// 2 MiB budget (dozens of buckets, spills through the log), each in a fresh
// process whose peak RSS is measured.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "bench_util.h"
#include "test_util.h"

namespace weaver {
namespace {

// Process baseline (binary, libraries, stacks) plus per-worker structures,
// measured at 4-8 MiB across budgets; 12 MiB leaves room for noise.
constexpr uint64_t kAllowedOverBudget = 12ull << 20;

// Each test's database in a directory of its own, and the peak RSS of the
// last weaver command it ran.
class MemoryBound : public ::testing::Test {
 protected:
  void SetUp() override {
#ifdef WEAVER_SANITIZED
    GTEST_SKIP() << "sanitizers inflate RSS";
#endif
  }
  // Generates an octree (weaver generate with `args`) and imports it into db
  // (their peaks unmeasured).
  void make_db(std::vector<std::string> args) {
    const std::string text = dir.file("o.txt");
    args.insert(args.begin(), {WEAVER_BINARY, "generate", text});
    uint64_t unmeasured = 0;
    ASSERT_FALSE(bench::run_program(args, &unmeasured).empty());
    ASSERT_FALSE(
        bench::run_program({WEAVER_BINARY, "import", db, "--octants", text}, &unmeasured).empty());
  }

  // `weaver args...`: its stdout ("" if it failed), and in rss its own peak
  // RSS, through peak_rss_runner (peak_rss_runner.cc: forked from this
  // process, a program's peak counts this process's own, whatever tests
  // ran in it before).
  std::string run_weaver(std::vector<std::string> args) {
    const std::string peak_file = dir.file("peak");
    args.insert(args.begin(), {PEAK_RSS_RUNNER, peak_file, WEAVER_BINARY});
    uint64_t runner_rss = 0;
    const std::string out = bench::run_program(args, &runner_rss);
    std::ifstream in(peak_file);
    rss = 0;
    if (!(in >> rss)) return "";
    return out;
  }

  testing::TempDir dir;
  uint64_t rss = 0;
  const std::string db = dir.file("db");
};

TEST_F(MemoryBound, ExtractStaysWithinBudgetOnAMeshFarLargerThanIt) {
  make_db({"--kind", "sphere", "--level", "3", "--max-level", "8"});
  const uint64_t budget = 2ull << 20;
  for (const char* threads : {"1", "2"}) {
    const std::string out =
        run_weaver({"extract", db, "--memory", "2M", "--threads", threads, "--json"});
    ASSERT_FALSE(out.empty());
    auto r = bench::parse_flat_json(out);
    EXPECT_GT(std::stod(r["elements"]), 900000);
    EXPECT_GT(std::stod(r["buckets"]), 20);
    EXPECT_GT(std::stod(r["spilled_to_disk"]), 0);
    EXPECT_LE(rss, budget + kAllowedOverBudget) << threads << " threads: peak RSS " << rss;
  }
}

// Balance of half a million random leaves down to level 14 (millions of
// parents and required octants through sorters and spools) with a 1 MiB
// budget.  Before the parents went through spools, the per-level sorters'
// merge buffers alone took 18 MB here.
TEST_F(MemoryBound, BalanceStaysWithinBudgetOnAnOctreeFarLargerThanIt) {
  make_db({"--kind", "random", "--leaves", "500000", "--max-level", "14"});
  const std::string out = run_weaver({"balance", db, "--memory", "1M"});
  ASSERT_NE(out.find("balanced 500"), std::string::npos) << out;
  EXPECT_LE(rss, (1ull << 20) + kAllowedOverBudget) << "peak RSS " << rss;
  const std::string check = bench::run_program({WEAVER_BINARY, "balance", db, "--check"}, &rss);
  EXPECT_NE(check.find("2:1 balanced"), std::string::npos) << check;
}

// Every command that reads a mesh, at a 16 MiB budget, on a mesh whose
// tables (12 MB) and whose work (a partition's (node, part) pairs, 8 for
// each of 2.9M elements, 376 MB; exports of 400 MB) are far past it.  The
// stored partition's report is the one that was not: with both meshes
// open (the one that made the partition, the one that reports it) and the
// sort's scratch made afresh at each spill, it peaked at 31.5 MiB.
TEST_F(MemoryBound, EveryCommandOnAMeshFarLargerThanItsBudgetStaysWithinIt) {
  ASSERT_FALSE(bench::run_program({WEAVER_BINARY, "mesh", db, "--model", "basin", "--freq", "0.5",
                                   "--domain", "50000,50000,37500", "--quiet"},
                                  &rss)
                   .empty());
  const std::string points = dir.file("points.txt");
  {
    std::ofstream f(points);
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> across(0, 50000), down(0, 37500);
    for (int i = 0; i < 20000; ++i)
      f << across(rng) << ' ' << across(rng) << ' ' << down(rng) << '\n';
  }
  // (query prints no progress, so takes no --quiet.)
  const std::vector<std::vector<std::string>> commands = {
      {"verify", db, "--quiet"},
      {"aggregate", db, "--quiet"},
      {"boundary", db, "--quiet"},
      {"export", db, "--format", "vtu", "--out", dir.file("mesh.vtu"), "--quiet"},
      {"export", db, "--format", "raw", "--out", dir.file("raw"), "--quiet"},
      {"export", db, "--format", "metis", "--out", dir.file("mesh.graph"), "--quiet"},
      {"export", db, "--format", "csv", "--out", dir.file("csv"), "--quiet"},
      {"partition", db, "--parts", "8", "--quiet"},
      {"query", db, "locate", "--points", points, "--units", "m"},
  };
  for (std::vector<std::string> args : commands) {
    const std::string what = args[0] + " " + (args.size() > 2 ? args[2] : "");
    args.insert(args.end(), {"--memory", "16M"});
    const std::string out = run_weaver(args);
    ASSERT_FALSE(out.empty()) << what;
    EXPECT_LE(rss, (16ull << 20) + kAllowedOverBudget) << what << ": peak RSS " << rss;
  }
  // The partition's sort left no scratch files.
  for (const auto& e : std::filesystem::directory_iterator(db)) {
    EXPECT_EQ(e.path().filename().string().rfind("tmp-", 0), std::string::npos) << e.path();
  }
}

}  // namespace
}  // namespace weaver
