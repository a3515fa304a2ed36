// A bucket's nodal pixels as words (extract/node_words.h): each offset once,
// its masks ORed, whether or not the table grows, against a std::map.
#include "extract/node_words.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <map>
#include <random>
#include <vector>

namespace weaver {
namespace {

// Adds n pixels of offsets below 2^bits (repeats among them) to a table
// sized for `expected`, and checks take() against a map.
void check(size_t expected, size_t n, int bits, uint64_t seed) {
  std::mt19937_64 rng(seed);
  NodeWords words;
  std::map<uint64_t, uint8_t> want;
  for (int round = 0; round < 2; ++round) {  // the second reuses the table
    words.reset(expected);
    want.clear();
    for (size_t i = 0; i < n; ++i) {
      // Half the offsets from a few hundred, so that many repeat.
      const uint64_t offset = (i % 2 ? rng() % 300 : rng()) & ((uint64_t{1} << bits) - 1);
      const uint8_t mask = static_cast<uint8_t>(1u << (rng() % 8));
      words.add(offset, mask);
      want[offset] |= mask;
    }
    std::vector<uint64_t> out;
    const uint64_t all = words.take(&out);
    ASSERT_EQ(out.size(), want.size());
    ASSERT_EQ(words.size(), want.size());
    uint64_t offsets = 0;  // the offsets ORed
    for (const auto& [offset, mask] : want) offsets |= offset;
    EXPECT_EQ(all >> 8, offsets);
    std::sort(out.begin(), out.end());
    size_t i = 0;
    for (const auto& [offset, mask] : want) {
      EXPECT_EQ(out[i] >> 8, offset);
      EXPECT_EQ(static_cast<uint8_t>(out[i]), mask);
      ++i;
    }
  }
}

TEST(NodeWords, EachOffsetOnceWithItsMasksORed) { check(5000, 4000, 20, 1); }

TEST(NodeWords, GrowsPastWhatItWasSizedFor) { check(10, 20000, 30, 2); }

TEST(NodeWords, HoldsTheWidestOffsets) { check(1000, 1000, NodeWords::kOffsetBits, 3); }

}  // namespace
}  // namespace weaver
