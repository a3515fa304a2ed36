// Extraction stays within its memory budget plus a small constant, whatever
// the mesh size: a mesh whose working set would be ~48 MB is extracted with a
// 2 MiB budget (dozens of buckets, spills through the log), in a fresh
// process whose peak RSS is measured.
#include <gtest/gtest.h>

#include "bench_util.h"
#include "test_util.h"

namespace weaver {
namespace {

// Process baseline (binary, libraries, stacks) plus per-worker structures,
// measured at 4-8 MiB across budgets; 12 MiB leaves room for noise.
constexpr uint64_t kAllowedOverBudget = 12ull << 20;

// Generates an octree (weaver generate with `args`) and imports it into db.
void make_db(const testing::TempDir& dir, std::vector<std::string> args, const std::string& db) {
  uint64_t rss = 0;
  const std::string text = dir.file("o.txt");
  args.insert(args.begin(), {WEAVER_BINARY, "generate", text});
  ASSERT_FALSE(bench::run_program(args, &rss).empty());
  ASSERT_FALSE(bench::run_program({WEAVER_BINARY, "import", db, "--octants", text}, &rss).empty());
}

TEST(MemoryBound, ExtractStaysWithinBudgetOnAMeshFarLargerThanIt) {
#ifdef WEAVER_SANITIZED
  GTEST_SKIP() << "sanitizers inflate RSS";
#endif
  testing::TempDir dir;
  uint64_t rss = 0;
  const std::string db = dir.file("db");
  make_db(dir, {"--kind", "sphere", "--level", "3", "--max-level", "8"}, db);
  const uint64_t budget = 2ull << 20;
  for (const char* threads : {"1", "2"}) {
    const std::string out = bench::run_program(
        {WEAVER_BINARY, "extract", db, "--memory", "2M", "--threads", threads, "--json"}, &rss);
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
TEST(MemoryBound, BalanceStaysWithinBudgetOnAnOctreeFarLargerThanIt) {
#ifdef WEAVER_SANITIZED
  GTEST_SKIP() << "sanitizers inflate RSS";
#endif
  testing::TempDir dir;
  uint64_t rss = 0;
  const std::string db = dir.file("db");
  make_db(dir, {"--kind", "random", "--leaves", "500000", "--max-level", "14"}, db);
  const std::string out =
      bench::run_program({WEAVER_BINARY, "balance", db, "--memory", "1M"}, &rss);
  ASSERT_NE(out.find("balanced 500"), std::string::npos) << out;
  EXPECT_LE(rss, (1ull << 20) + kAllowedOverBudget) << "peak RSS " << rss;
  const std::string check = bench::run_program({WEAVER_BINARY, "balance", db, "--check"}, &rss);
  EXPECT_NE(check.find("2:1 balanced"), std::string::npos) << check;
}

}  // namespace
}  // namespace weaver
