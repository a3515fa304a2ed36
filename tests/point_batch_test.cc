// cli/point_batch: a batch shared among threads (its lookups and its rows
// split among helper Explorers, a thread each) writes exactly the rows one
// thread writes, in every output mode; and a batch whose lane lets it
// answer more points at a time writes them too.  Runs under
// ThreadSanitizer too (the "tsan" preset takes *Thread* tests).
#include "cli/point_batch.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <string>

#include "test_mesh.h"
#include "test_octrees.h"

namespace weaver {
namespace {

// The rows of a batch of `points` (text lines), with `helpers` helpers and
// `batch_points` at a time (0: the Explorer's).
std::string rows_of(Explorer& ex, const std::vector<Explorer*>& helpers, const std::string& points,
                    cli::OutputMode mode, size_t batch_points) {
  char* out = nullptr;
  size_t out_size = 0;
  std::FILE* o = open_memstream(&out, &out_size);
  std::FILE* in = fmemopen(const_cast<char*>(points.data()), points.size(), "r");
  std::FILE* err = std::fopen("/dev/null", "w");
  cli::PointBatchOptions opt;
  opt.mode = mode;
  opt.helpers = helpers;
  opt.batch_points = batch_points;
  cli::PointBatchResult r;
  EXPECT_OK(cli::run_point_batch(ex, in, "points", opt, o, err, &r));
  std::fclose(in);
  std::fclose(err);
  std::fclose(o);
  std::string text(out, out_size);
  std::free(out);
  return text;
}

TEST(PointBatchThreads, HelpersAndLanesWriteWhatOneThreadWrites) {
  testing::TempDir dir;
  const std::string db =
      testing::build_mesh(testing::random_balanced(3, 2, 1, 1, 2, 4000, 10), dir);
  std::unique_ptr<Explorer> ex, helper;
  // A small budget: the Explorer's own batch is a few thousand points.
  ASSERT_OK(Explorer::open(db, MemoryBudget(2 << 20), &ex));
  ASSERT_OK(Explorer::open(db, MemoryBudget(2 << 20), &helper));
  std::string points;  // past the size a batch is shared at, with bad lines among them
  for (int i = 0; i < 60000; ++i) {
    points += i % 997 == 0
                  ? "not a point\n"
                  : std::to_string(i * 7919 % 1048576) + " " + std::to_string(i * 3571 % 1048576) +
                        " " + std::to_string(i * 997 % 262144) + "\n";
  }
  for (const cli::OutputMode mode : {cli::OutputMode::kJson, cli::OutputMode::kCsv}) {
    const std::string alone = rows_of(*ex, {}, points, mode, 0);
    ASSERT_GT(alone.size(), points.size());
    EXPECT_TRUE(rows_of(*ex, {helper.get()}, points, mode, 0) == alone);
    EXPECT_TRUE(rows_of(*ex, {helper.get()}, points, mode, 50000) == alone);
    EXPECT_TRUE(rows_of(*ex, {}, points, mode, 20000) == alone);
  }
}

}  // namespace
}  // namespace weaver
