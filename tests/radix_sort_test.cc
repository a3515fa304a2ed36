// radix_sort and sort_records (the extraction buckets' sort) against
// std::sort, over the key spans that choose between radix and fallback.
#include "util/radix_sort.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "extract/bucket_worker.h"

namespace weaver {
namespace {

TEST(RadixSort, SortsByTheChosenBitsStably) {
  std::mt19937_64 rng(3);
  std::vector<uint64_t> scratch;
  for (int t = 0; t < 200; ++t) {
    const int first = static_cast<int>(rng() % 12);
    const int bits = 1 + static_cast<int>(rng() % (64 - first));
    const size_t n = rng() % 5000;
    std::vector<uint64_t> values(n);
    for (uint64_t& v : values) {
      const uint64_t sort_part = bits == 64 ? rng() : rng() & ((uint64_t{1} << bits) - 1);
      v = sort_part << first | (rng() & ((uint64_t{1} << first) - 1));
    }
    std::vector<uint64_t> want = values;
    // Stable on the sorted bits: the low bits keep their input order.
    std::stable_sort(want.begin(), want.end(),
                     [first](uint64_t a, uint64_t b) { return (a >> first) < (b >> first); });
    radix_sort(values, first, bits, scratch);
    ASSERT_EQ(values, want) << "first " << first << " bits " << bits << " n " << n;
  }
}

// radix_sort_by skips the digits every key shares: keys that differ only
// in a few middle bits, or only in the top ones, or not at all.
TEST(RadixSort, ByKeyIsStableWhateverBitsTheKeysShare) {
  std::mt19937_64 rng(5);
  std::vector<std::pair<uint64_t, uint32_t>> scratch;
  for (int t = 0; t < 300; ++t) {
    const int low = static_cast<int>(rng() % 64);
    const int span = static_cast<int>(rng() % (65 - low));
    const uint64_t fixed = rng();
    const uint64_t mask = span == 64 ? ~uint64_t{0} : ((uint64_t{1} << span) - 1) << low;
    std::vector<std::pair<uint64_t, uint32_t>> items(rng() % 4000);
    for (uint32_t i = 0; i < items.size(); ++i) items[i] = {(fixed & ~mask) | (rng() & mask), i};
    auto want = items;
    std::stable_sort(want.begin(), want.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    radix_sort_by(items, scratch, [](const auto& p) { return p.first; });
    ASSERT_EQ(items, want) << "low " << low << " span " << span;
  }
}

TEST(SortRecords, MatchesStdSortForNarrowAndWideKeySpans) {
  std::mt19937_64 rng(4);
  std::vector<uint64_t> packed, scratch;
  for (int t = 0; t < 300; ++t) {
    const int span_bits = 1 + static_cast<int>(rng() % 63);  // past 56: the fallback
    const int zeros = static_cast<int>(rng() % 20);
    const uint64_t base = rng() >> 2;
    std::vector<SpillRecord> records(rng() % 3000);
    std::vector<uint64_t> keys;
    for (SpillRecord& r : records) {
      uint64_t offset = (span_bits == 64 ? rng() : rng() & ((uint64_t{1} << span_bits) - 1));
      offset = offset >> zeros << zeros;
      r = {(base + offset) & ((uint64_t{1} << 63) - 1), static_cast<uint8_t>(rng())};
    }
    std::sort(records.begin(), records.end(),
              [](const SpillRecord& a, const SpillRecord& b) { return a.key < b.key; });
    records.erase(
        std::unique(records.begin(), records.end(),
                    [](const SpillRecord& a, const SpillRecord& b) { return a.key == b.key; }),
        records.end());
    std::vector<SpillRecord> shuffled = records;
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    sort_records(shuffled, packed, scratch);
    ASSERT_EQ(shuffled.size(), records.size());
    for (size_t i = 0; i < records.size(); ++i) {
      ASSERT_EQ(shuffled[i].key, records[i].key) << "span " << span_bits << " at " << i;
      ASSERT_EQ(shuffled[i].mask, records[i].mask);
    }
  }
}

}  // namespace
}  // namespace weaver
