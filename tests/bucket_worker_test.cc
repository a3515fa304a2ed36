// The pieces of a bucket's work that extraction's results rest on, each
// against the obvious way: a leaf's corners against decoding the octant,
// and a spill run against a map of every key added.
#include "extract/bucket_worker.h"

#include <gtest/gtest.h>

#include <map>
#include <random>
#include <vector>

#include "test_util.h"

namespace weaver {
namespace {

// A random octant of `level`, near either side of the root on each axis as
// often as anywhere (a far corner there carries into the root's edge bit).
Octant random_octant(std::mt19937_64& rng, int level) {
  const uint32_t cells = uint32_t{1} << level, size = uint32_t{1} << (kMaxLevel - level);
  auto coordinate = [&] {
    const uint32_t c = static_cast<uint32_t>(rng() % cells);
    const uint32_t pick = static_cast<uint32_t>(rng() % 4);
    return (pick == 0 ? 0 : pick == 1 ? cells - 1 : c) * size;
  };
  return {coordinate(), coordinate(), coordinate(), static_cast<uint8_t>(level)};
}

TEST(LeafCornerKeys, AreTheOctantsCornersEncoded) {
  std::mt19937_64 rng(84);
  uint64_t corners[8];
  for (int i = 0; i < 20000; ++i) {
    const Octant o = random_octant(rng, static_cast<int>(rng() % (kMaxLevel + 1)));
    leaf_corner_keys(octant_key(o), corners);
    for (int k = 0; k < 8; ++k) {
      ASSERT_EQ(corners[k], morton_encode(octant_corner(o, k)))
          << describe_octant(o) << " corner " << k;
    }
  }
}

// Keys that share their low zero bits but lie up to 2^59 past a base that
// does not (a bucket's end is its next leaf's code, its far corners those
// of its own, finer leaves) come back once each, sorted, masks ORed.
TEST(SpillRunTest, KeysFarPastAnUnalignedBaseComeBackSortedAndMerged) {
  testing::TempDir dir;
  std::mt19937_64 rng(7);
  for (int zeros : {0, 3, 15, 27}) {
    SpillStore store(dir.file("spill" + std::to_string(zeros)), 1 << 20);
    const uint64_t base = (uint64_t{1} << 40) + 5;  // no multiple of 2^zeros but for 0
    const uint64_t reach = uint64_t{1} << 59;
    std::map<uint64_t, uint8_t> want;
    SpillRun run;
    run.begin(base, base + reach, zeros);
    for (int i = 0; i < 5000; ++i) {
      // Half near the base, half anywhere up to the bound; a tenth repeats.
      uint64_t key = base + (i % 2 == 0 ? rng() % 4096 : rng() % reach);
      key = (key + (uint64_t{1} << zeros) - 1) >> zeros << zeros;  // the next multiple
      if (key > base + reach) continue;
      if (i % 10 == 0 && !want.empty()) key = want.begin()->first;
      const auto mask = static_cast<uint8_t>(1u << (rng() % 8));
      want[key] |= mask;
      run.add(key, mask);
    }
    ASSERT_OK(run.flush(store));
    std::vector<SpillRecord> got;
    ASSERT_OK(store.take_below(UINT64_MAX, &got));
    ASSERT_EQ(got.size(), want.size()) << "zeros " << zeros;
    size_t i = 0;
    for (const auto& [key, mask] : want) {
      EXPECT_EQ(got[i].key, key) << "zeros " << zeros << " record " << i;
      EXPECT_EQ(got[i].mask, mask) << "zeros " << zeros << " record " << i;
      ++i;
    }
  }
}

}  // namespace
}  // namespace weaver
