// cli/point_batch: a batch shared among threads (its lookups and its rows
// split among helper Explorers, a thread each) writes exactly the rows one
// thread writes, in every output mode; and a batch whose lane lets it
// answer more points at a time writes them too; a write that fails fails
// the batch.  Runs under
// ThreadSanitizer too (the "tsan" preset takes *Thread* tests).
#include "cli/point_batch.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <random>
#include <string>

#include "test_mesh.h"
#include "test_octrees.h"

namespace weaver {
namespace {

// The rows of a batch of `points` (text lines), with `helpers` helpers and
// `batch_points` at a time (0: the Explorer's); with `errors`, what it said
// of the lines that are no points.
std::string rows_of(Explorer& ex, const std::vector<Explorer*>& helpers, const std::string& points,
                    cli::OutputMode mode, size_t batch_points, std::string* errors = nullptr) {
  char* out = nullptr;
  size_t out_size = 0;
  std::FILE* o = open_memstream(&out, &out_size);
  std::FILE* in = fmemopen(const_cast<char*>(points.data()), points.size(), "r");
  char* said = nullptr;
  size_t said_size = 0;
  std::FILE* err = open_memstream(&said, &said_size);
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
  if (errors != nullptr) *errors = std::string(said, said_size);
  std::free(said);
  return text;
}

TEST(PointBatchThreads, HelpersAndLanesWriteWhatOneThreadWrites) {
  testing::TempDir dir;
  const std::vector<Octant> leaves = testing::random_balanced(3, 2, 1, 1, 2, 4000, 10);
  const std::string db = testing::build_mesh(leaves, dir);
  std::unique_ptr<Explorer> ex, helper;
  // A small budget: the Explorer's own batch is a few thousand points.
  ASSERT_OK(Explorer::open(db, MemoryBudget(2 << 20), &ex));
  ASSERT_OK(Explorer::open(db, MemoryBudget(2 << 20), &helper));
  // Past the size a batch is shared at: a point in a leaf picked at random
  // (so that every share of the sorted batch has points to answer), with bad
  // lines and points past the domain's far corner among them.
  std::string points;
  std::mt19937_64 rng(11);
  for (int i = 0; i < 60000; ++i) {
    const Octant& o = leaves[rng() % leaves.size()];
    const uint32_t e = octant_edge(o);
    points += i % 997 == 0 ? "not a point\n"
              : i % 101 == 0
                  ? "1048575 1048575 1048575\n"
                  : std::to_string(o.x + rng() % e) + " " + std::to_string(o.y + rng() % e) + " " +
                        std::to_string(o.z + rng() % e) + "\n";
  }
  // The lines that are no points are named in input order, each with its
  // number, alone and with a helper.
  std::string expected_errors;
  for (int i = 0; i < 60000; i += 997) {
    expected_errors += "points:" + std::to_string(i + 1) +
                       ": 'not' is not a whole number of ticks (0 to 4294967294)\n";
  }
  for (const cli::OutputMode mode : {cli::OutputMode::kJson, cli::OutputMode::kCsv}) {
    std::string errors;
    const std::string alone = rows_of(*ex, {}, points, mode, 0, &errors);
    EXPECT_EQ(errors, expected_errors);
    ASSERT_GT(alone.size(), points.size());
    // Inside but for the far corner's (a share left unanswered would show).
    const auto count = [&](const std::string& word) {
      size_t n = 0;
      for (size_t at = 0; (at = alone.find(word, at)) != std::string::npos; at += word.size()) ++n;
      return n;
    };
    EXPECT_GT(count("inside"), 58000u);
    EXPECT_GT(count("outside"), 500u);
    EXPECT_TRUE(rows_of(*ex, {helper.get()}, points, mode, 0, &errors) == alone);
    EXPECT_EQ(errors, expected_errors);
    EXPECT_TRUE(rows_of(*ex, {helper.get()}, points, mode, 50000) == alone);
    EXPECT_TRUE(rows_of(*ex, {}, points, mode, 20000) == alone);
  }
  // A full disk: the batch fails with the write's error, on one thread and
  // shared (where one thread writes while the others format).
  for (const std::vector<Explorer*>& helpers :
       {std::vector<Explorer*>{}, std::vector<Explorer*>{helper.get()}}) {
    std::FILE* full = std::fopen("/dev/full", "w");
    ASSERT_NE(full, nullptr);
    std::FILE* in = fmemopen(const_cast<char*>(points.data()), points.size(), "r");
    std::FILE* err = std::fopen("/dev/null", "w");
    cli::PointBatchOptions opt;
    opt.mode = cli::OutputMode::kCsv;
    opt.helpers = helpers;
    opt.batch_points = 100000;  // one batch, shared
    cli::PointBatchResult r;
    const Status st = cli::run_point_batch(*ex, in, "points", opt, full, err, &r);
    EXPECT_FALSE(st.ok()) << helpers.size() << " helpers";
    EXPECT_NE(st.message().find("writing the answers"), std::string::npos) << st.message();
    std::fclose(in);
    std::fclose(err);
    std::fclose(full);
  }
}

}  // namespace
}  // namespace weaver
