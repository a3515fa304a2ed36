// The leaf directory's search against a linear scan of its fences.
#include "storage/leaf_directory.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace weaver {
namespace {

// The last i with fences[i] <= key (fences[0] is 0, so there is one).
uint32_t last_at_or_below(const std::vector<uint64_t>& fences, uint64_t key) {
  uint32_t j = 0;
  for (uint32_t i = 0; i < fences.size(); ++i) {
    if (fences[i] <= key) j = i;
  }
  return j;
}

TEST(LeafDirectoryTest, FindsTheLastFenceAtOrBelowEveryKey) {
  std::mt19937_64 rng(7);
  // Sizes around the chunk of 16, and larger; fences spaced by 1 to 1000,
  // some repeated, some near the top of the key space.
  for (const uint32_t leaves : {1u, 2u, 15u, 16u, 17u, 31u, 32u, 33u, 255u, 1000u, 4099u}) {
    std::vector<uint64_t> fences = {0};
    const uint64_t gap = 1 + rng() % 1000;
    while (fences.size() < leaves) fences.push_back(fences.back() + rng() % (2 * gap));
    if (leaves > 2) fences.back() = UINT64_MAX - rng() % 2;
    LeafDirectory dir;
    for (uint32_t i = 0; i < leaves; ++i) dir.add(fences[i], 1000 + i, 10ull * i);
    ASSERT_EQ(dir.size(), leaves);
    std::vector<uint64_t> keys = {0, 1, UINT64_MAX, UINT64_MAX - 1};
    for (const uint64_t f : fences) keys.insert(keys.end(), {f - 1, f, f + 1});
    for (int i = 0; i < 2000; ++i)
      keys.push_back(rng() % (fences[leaves > 2 ? leaves - 2 : 0] + 2000));
    for (const uint64_t k : keys) {
      const uint32_t want = last_at_or_below(fences, k);
      const uint32_t got = dir.find(k);
      ASSERT_EQ(got, want) << leaves << " leaves, key " << k;
      ASSERT_EQ(dir.page(got), 1000 + want);
      ASSERT_EQ(dir.first_rank(got), 10ull * want);
      ASSERT_EQ(dir.fence(got), fences[want]);
    }
  }
}

TEST(LeafDirectoryTest, ClearEmptiesItAndItsMemoryIsWhatBytesForSays) {
  LeafDirectory dir;
  EXPECT_TRUE(dir.empty());
  for (uint32_t i = 0; i < 100; ++i) dir.add(i * 5, i + 1, i);
  EXPECT_FALSE(dir.empty());
  EXPECT_EQ(dir.last_fence(), 99u * 5);
  // 7 chunks of 16 fences (8 bytes) and pages (4), a top entry each, and a
  // rank per leaf.
  EXPECT_EQ(LeafDirectory::bytes_for(100), 7 * (16 * 12 + 8) + 100 * 8u);
  dir.clear();
  EXPECT_TRUE(dir.empty());
  EXPECT_EQ(dir.size(), 0u);
}

}  // namespace
}  // namespace weaver
