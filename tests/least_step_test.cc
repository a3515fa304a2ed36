// construct/least_step.h: the least edge / vp of a run of leaves, found from
// each level's largest vp, must be what a division a leaf in order finds
// (the value and the first leaf that has it), on random runs with ties
// within a level and across levels, and with vps that are not positive.
#include "construct/least_step.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "schema/octant.h"

namespace weaver {
namespace {

// The obvious answer: every leaf divided, in order, the first of equals kept.
void divide_each(const std::vector<uint64_t>& keys, const std::vector<std::byte>& payloads,
                 size_t bytes, double tick_m, uint64_t before, double* least, uint64_t* element) {
  for (size_t i = 0; i < keys.size(); ++i) {
    float vp;
    std::memcpy(&vp, payloads.data() + i * bytes, 4);
    const double dt = octant_edge(octant_key_level(keys[i])) * tick_m / vp;
    if (dt < *least) *least = dt, *element = before + i;
  }
}

struct Leaves {
  std::vector<uint64_t> keys;
  std::vector<std::byte> payloads;
};

// n leaves of levels [lo, hi] with vps from a few values (repeats within a
// level), some a power of two apart so that levels tie; `odd` mixes in a
// zero, a negative vp or a NaN now and then.
Leaves random_run(size_t n, size_t bytes, int lo, int hi, bool odd, std::mt19937_64& rng) {
  const float values[] = {1500.f, 3000.f, 750.f, 2600.5f, 5201.f, 1300.25f};
  const float strange[] = {0.f, -0.f, -1200.f, std::numeric_limits<float>::quiet_NaN(),
                           std::numeric_limits<float>::infinity()};
  Leaves r;
  r.payloads.resize(n * bytes);
  for (size_t i = 0; i < n; ++i) {
    const int level = lo + static_cast<int>(rng() % (hi - lo + 1));
    // Keys need not be sorted here: only their levels count.
    r.keys.push_back(octant_key(Octant{0, 0, 0, static_cast<uint8_t>(level)}));
    float vp = values[rng() % 6];
    if (odd && rng() % 50 == 0) vp = strange[rng() % 5];
    std::memcpy(r.payloads.data() + i * bytes, &vp, 4);
    const float other = float(rng() % 1000);
    std::memcpy(r.payloads.data() + i * bytes + 4, &other, 4);
  }
  return r;
}

TEST(LeastStep, EachLevelsLargestVpGivesTheDivisionsAnswer) {
  std::mt19937_64 rng(51);
  int odd_runs = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const size_t bytes = trial % 2 == 0 ? 12 : 20;
    const bool odd = trial % 5 == 0;
    const int lo = static_cast<int>(rng() % 18);
    const int hi = lo + static_cast<int>(rng() % 3);
    Leaves r = random_run(1 + rng() % 300, bytes, lo, hi, odd, rng);
    // A least found before, sometimes below this run's, sometimes above.
    const double start = trial % 3 == 0 ? HUGE_VAL : 1e-3 * double(rng() % 4000);
    const double tick_m = trial % 4 == 0 ? 0.0953674 : 1.0;
    double want = start, got = start;
    uint64_t want_at = 7, got_at = 7;
    divide_each(r.keys, r.payloads, bytes, tick_m, 1000, &want, &want_at);
    note_least_step(r.keys.data(), r.payloads.data(), r.keys.size(), bytes, tick_m, 1000, &got,
                    &got_at);
    ASSERT_EQ(std::memcmp(&got, &want, sizeof got), 0) << trial << ": " << got << " " << want;
    ASSERT_EQ(got_at, want_at) << trial;
    // Counted from the run itself: a run that holds a vp not positive.
    bool strange = false;
    for (size_t i = 0; i < r.keys.size(); ++i) {
      float vp;
      std::memcpy(&vp, r.payloads.data() + i * bytes, 4);
      strange = strange || !(vp > 0);
    }
    odd_runs += strange;
  }
  EXPECT_GT(odd_runs, 0);
}

// Two levels tie exactly (an edge twice the other over a vp twice the
// other): the first leaf of the two has the step.
TEST(LeastStep, ATieAcrossLevelsGoesToTheFirstLeaf) {
  for (bool coarse_first : {true, false}) {
    const uint64_t fine = octant_key(Octant{0, 0, 0, 9}), coarse = octant_key(Octant{0, 0, 0, 8});
    const std::vector<uint64_t> keys = {fine, coarse_first ? coarse : fine,
                                        coarse_first ? fine : coarse, fine};
    const float vps[] = {100.f, coarse_first ? 2000.f : 1000.f, coarse_first ? 1000.f : 2000.f,
                         999.f};
    std::vector<std::byte> payloads(4 * 12);
    for (int i = 0; i < 4; ++i) std::memcpy(payloads.data() + i * 12, &vps[i], 4);
    double least = HUGE_VAL;
    uint64_t at = 0;
    note_least_step(keys.data(), payloads.data(), 4, 12, 0.5, 0, &least, &at);
    EXPECT_EQ(least, octant_edge(9) * 0.5 / 1000.0);
    EXPECT_EQ(at, 1u);
  }
}

}  // namespace
}  // namespace weaver
