// SpillStore against a multiset: buckets, increasing ranges of keys taken
// in order, get back exactly the records added with keys in their range,
// whether they waited in memory or in the spill log.
#include "extract/spill_store.h"

#include <gtest/gtest.h>
#include <malloc.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "test_util.h"

namespace weaver {
namespace {

using Records = std::vector<std::pair<uint64_t, int>>;

// The records as (key, mask) pairs, sorted: a bucket's records in any order.
Records sorted(const std::vector<SpillRecord>& v) {
  Records out;
  for (const SpillRecord& r : v) out.push_back({r.key, r.mask});
  std::sort(out.begin(), out.end());
  return out;
}

// Walks buckets [bounds[b], bounds[b+1]) in order as extraction does: bucket
// b takes the keys below its end, then adds one sorted run of keys at or past
// its end (mostly in the next few buckets, some far ahead).
void run(uint64_t cap, uint64_t seed, uint64_t* written) {
  testing::TempDir dir;
  std::mt19937_64 rng(seed);
  const size_t n = 300;
  std::vector<uint64_t> bounds = {0};
  for (size_t b = 0; b < n; ++b) bounds.push_back(bounds.back() + 1 + rng() % 1000);
  bounds.back() = UINT64_MAX;
  std::multiset<std::pair<uint64_t, int>> waiting;
  {
    SpillStore store(dir.file("spill"), cap);
    for (size_t b = 0; b < n; ++b) {
      std::vector<SpillRecord> got;
      ASSERT_OK(store.take_below(bounds[b + 1], &got));
      Records want(waiting.begin(), waiting.lower_bound({bounds[b + 1], 0}));
      waiting.erase(waiting.begin(), waiting.lower_bound({bounds[b + 1], 0}));
      ASSERT_EQ(sorted(got), want) << "bucket " << b;
      if (b + 1 == n) break;
      std::vector<SpillRecord> run;
      const int adds = static_cast<int>(rng() % 200);
      for (int i = 0; i < adds; ++i) {
        const size_t to = std::min(n - 1, b + 1 + (rng() % 8 == 0 ? rng() % n : rng() % 4));
        const uint64_t span = std::min<uint64_t>(bounds[to + 1] - bounds[to], 5000);
        run.push_back({bounds[to] + rng() % span, static_cast<uint8_t>(rng())});
      }
      std::sort(run.begin(), run.end(),
                [](const SpillRecord& x, const SpillRecord& y) { return x.key < y.key; });
      for (const SpillRecord& r : run) waiting.insert({r.key, r.mask});
      ASSERT_OK(store.add_run(std::move(run)));
    }
    EXPECT_TRUE(waiting.empty());
    EXPECT_TRUE(store.empty());
    EXPECT_EQ(store.memory_bytes(), 0u);
    *written = store.records_written();
  }
  // The scratch directory goes with the store.
  EXPECT_FALSE(std::filesystem::exists(dir.file("spill")));
}

TEST(SpillStoreTest, RecordsComeBackFromMemory) {
  uint64_t written = 0;
  run(1ull << 30, 1, &written);
  EXPECT_EQ(written, 0u);
}

TEST(SpillStoreTest, RecordsComeBackFromTheSpillLogUnderASmallCap) {
  for (const uint64_t cap : {uint64_t{1}, uint64_t{256}, uint64_t{4096}}) {
    uint64_t written = 0;
    run(cap, cap, &written);
    EXPECT_GT(written, 0u) << "cap " << cap;
  }
}

// take_first hands out the waiting records from the smallest key on, a key's
// records from every run together, at least as many as asked (unless fewer
// wait) and no key more than needed; *end is the first key left waiting.
TEST(SpillStoreTest, TakeFirstTakesTheSmallestKeysWholeAndSaysWhereItStopped) {
  for (const uint64_t cap : {uint64_t{1} << 30, uint64_t{512}}) {
    testing::TempDir dir;
    std::mt19937_64 rng(cap);
    SpillStore store(dir.file("spill"), cap);
    std::multiset<std::pair<uint64_t, int>> waiting;
    for (int r = 0; r < 40; ++r) {
      std::vector<SpillRecord> run;
      uint64_t key = rng() % 50;
      for (int i = 0; i < 300; ++i) run.push_back({key += rng() % 20, uint8_t(1u << (r % 8))});
      for (const SpillRecord& x : run) waiting.insert({x.key, x.mask});
      ASSERT_OK(store.add_run(std::move(run)));
    }
    uint64_t end = 0;
    while (!waiting.empty()) {
      std::vector<SpillRecord> got;
      const size_t want = 1 + rng() % 500;
      ASSERT_OK(store.take_first(want, &end, &got));
      const auto stop = waiting.lower_bound({end, 0});
      ASSERT_EQ(sorted(got), Records(waiting.begin(), stop));
      waiting.erase(waiting.begin(), stop);
      if (!waiting.empty()) {
        ASSERT_EQ(end, waiting.begin()->first);
        ASSERT_GE(got.size(), want);
        // Without its largest key, it would have taken too few.
        const uint64_t last = sorted(got).back().first;
        const auto without = std::count_if(got.begin(), got.end(),
                                           [&](const SpillRecord& x) { return x.key < last; });
        ASSERT_LT(static_cast<size_t>(without), want);
      }
    }
    EXPECT_EQ(end, UINT64_MAX);
    EXPECT_TRUE(store.empty());
  }
}

// A run handed over in a buffer far larger than its records (extraction's
// buffers held every corner before duplicates merged) is counted at that
// buffer, and one moved to the log gives its buffer back: the heap in use
// stays near the cap however many runs wait.  (At 2 Hz, runs that kept
// their buffers took extraction to 462 MB under --memory 256M.)
TEST(SpillStoreTest, RunsCountAndGiveBackTheirWholeBuffers) {
  testing::TempDir dir;
  const uint64_t cap = 1 << 20;
  SpillStore store(dir.file("spill"), cap);
  const size_t before = mallinfo2().uordblks;
  for (uint64_t r = 0; r < 200; ++r) {
    std::vector<SpillRecord> run;
    run.reserve(50000);  // 800 KB
    for (uint64_t i = 0; i < 1000; ++i) run.push_back({r * 1000000 + i, 1});
    ASSERT_OK(store.add_run(std::move(run)));
    ASSERT_LE(store.memory_bytes(), cap);
  }
  const size_t grown = mallinfo2().uordblks - before;
  EXPECT_LT(grown, 4 * cap);  // not 200 buffers of 800 KB
  std::vector<SpillRecord> got;
  ASSERT_OK(store.take_below(UINT64_MAX, &got));
  EXPECT_EQ(got.size(), 200000u);
  EXPECT_EQ(store.memory_bytes(), 0u);
}

}  // namespace
}  // namespace weaver
