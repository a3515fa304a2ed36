// util/key_set.h, balance's set of one level's octant keys: the same answers
// as std::set for dense blocks, planes, scattered octants and the neighbours
// of all of them, at every level from the root's to 19, in tables of one
// region and of many.
#include "util/key_set.h"

#include <gtest/gtest.h>

#include <random>
#include <set>
#include <vector>

#include "schema/octant.h"

namespace weaver {
namespace {

std::vector<uint64_t> octants_of_level(int level, int style, std::mt19937_64& rng) {
  const uint32_t cells = 1u << level, e = octant_edge(level);
  const uint32_t span = std::min<uint32_t>(cells, 24);  // a box of up to 24^3 cells
  const uint32_t x0 = rng() % (cells - span + 1), y0 = rng() % (cells - span + 1);
  const uint32_t z0 = rng() % (cells - span + 1);
  std::vector<uint64_t> keys;
  for (uint32_t k = 0; k < span; ++k)
    for (uint32_t j = 0; j < span; ++j)
      for (uint32_t i = 0; i < span; ++i) {
        const bool take = style == 0   ? true              // a dense box
                          : style == 1 ? k == span / 2     // a plane
                                       : rng() % 16 == 0;  // scattered
        if (take)
          keys.push_back(
              octant_key({(x0 + i) * e, (y0 + j) * e, (z0 + k) * e, static_cast<uint8_t>(level)}));
      }
  return keys;
}

TEST(KeySet, AnswersAsASetDoesForEveryLevelAndLayout) {
  std::mt19937_64 rng(9);
  for (int level = 0; level < kMaxLevel; ++level) {
    for (int style = 0; style < 3; ++style) {
      const std::vector<uint64_t> keys = octants_of_level(level, style, rng);
      const std::set<uint64_t> want(keys.begin(), keys.end());
      KeySet set;
      set.reset(keys.size());
      for (uint64_t k : keys) set.add(k);
      for (uint64_t k : keys) {
        ASSERT_TRUE(set.contains(k)) << "level " << level << " style " << style;
        for (const Direction& d : kAllDirections) {
          uint64_t n = 0;
          if (!octant_key_neighbour(k, d, &n)) continue;
          ASSERT_EQ(set.contains(n), want.count(n) == 1) << "level " << level << " style " << style;
        }
      }
    }
  }
}

}  // namespace
}  // namespace weaver
