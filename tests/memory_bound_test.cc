// Extraction stays within its memory budget plus a small constant, whatever
// the mesh size: a mesh whose working set would be ~48 MB is extracted with a
// 2 MiB budget (thousands of buckets, spills through the log), in a fresh
// process whose peak RSS is measured.
#include <gtest/gtest.h>

#include "bench_util.h"
#include "test_util.h"

namespace weaver {
namespace {

// Process baseline (binary, libraries, stacks) plus per-worker structures,
// measured at 4-8 MiB across budgets; 12 MiB leaves room for noise.
constexpr uint64_t kAllowedOverBudget = 12ull << 20;

TEST(MemoryBound, ExtractStaysWithinBudgetOnAMeshFarLargerThanIt) {
#ifdef WEAVER_SANITIZED
  GTEST_SKIP() << "sanitizers inflate RSS";
#endif
  testing::TempDir dir;
  uint64_t rss = 0;
  const std::string text = dir.file("o.txt"), db = dir.file("db");
  ASSERT_FALSE(bench::run_program({WEAVER_BINARY, "generate", text, "--kind", "sphere", "--level",
                                   "3", "--max-level", "8"},
                                  &rss)
                   .empty());
  ASSERT_FALSE(bench::run_program({WEAVER_BINARY, "import", db, "--octants", text}, &rss).empty());
  const uint64_t budget = 2ull << 20;
  for (const char* threads : {"1", "2"}) {
    const std::string out =
        bench::run_program({WEAVER_BINARY, "extract", db, "--memory", "2M", "--threads", threads,
                            "--json"},
                           &rss);
    ASSERT_FALSE(out.empty());
    auto r = bench::parse_flat_json(out);
    EXPECT_GT(std::stod(r["elements"]), 900000);
    EXPECT_GT(std::stod(r["buckets"]), 1000);
    EXPECT_LE(rss, budget + kAllowedOverBudget) << threads << " threads: peak RSS " << rss;
  }
}

}  // namespace
}  // namespace weaver
