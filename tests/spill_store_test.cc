// SpillStore against a map: buckets taken in increasing order get back
// exactly the records added to them, whether they waited in memory or in
// the spill log.
#include "extract/spill_store.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <random>
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

// Walks buckets 0..n-1 in order as extraction does: while at bucket b,
// records go only to later buckets; then b is taken.
void run(uint64_t cap, uint64_t seed, uint64_t* written) {
  testing::TempDir dir;
  std::mt19937_64 rng(seed);
  const uint64_t n = 300;
  std::map<uint64_t, std::vector<SpillRecord>> expected;
  {
    SpillStore store(dir.file("spill"), cap);
    for (uint64_t b = 0; b < n; ++b) {
      const int adds = static_cast<int>(rng() % 200);
      for (int i = 0; i < adds; ++i) {
        const uint64_t to = b + 1 + rng() % std::min<uint64_t>(8, n);  // mostly near
        const SpillRecord r{rng(), static_cast<uint8_t>(rng())};
        ASSERT_OK(store.add(to, r));
        expected[to].push_back(r);
      }
      if (!store.empty()) {
        ASSERT_GT(store.first_bucket(), b);
      }
      std::vector<SpillRecord> got;
      ASSERT_OK(store.take(b + 1, &got));
      ASSERT_EQ(sorted(got), sorted(expected[b + 1])) << "bucket " << b + 1;
      expected.erase(b + 1);
    }
    for (auto& [bucket, want] : expected) {  // the tail past the last bucket
      ASSERT_FALSE(store.empty());
      ASSERT_EQ(store.first_bucket(), bucket);
      std::vector<SpillRecord> got;
      ASSERT_OK(store.take(bucket, &got));
      ASSERT_EQ(sorted(got), sorted(want)) << "bucket " << bucket;
    }
    EXPECT_TRUE(store.empty());
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

}  // namespace
}  // namespace weaver
