// balance/window_plan.h: windows cover their leaves exactly, in order;
// they lengthen after windows that held less than the first estimate, and
// shorten at once after one that held more or had to be cut.
#include "balance/window_plan.h"

#include <gtest/gtest.h>

namespace weaver {
namespace {

constexpr uint64_t kSlot = 64ull << 20;

TEST(WindowPlan, WindowsCoverTheLeavesInOrderWithinTheLongest) {
  for (uint64_t n : {1ull, 1023ull, 1024ull, 5000ull, 3000000ull}) {
    WindowPlan plan(17, n, kSlot, 200, 700000);
    uint64_t at = 17;
    int windows = 0;
    while (plan.more()) {
      uint64_t first = 0, count = 0;
      plan.next(&first, &count);
      EXPECT_EQ(first, at);
      EXPECT_GT(count, 0u);
      EXPECT_LE(count, 700000u);
      at += count;
      // Cheap windows: the next ones as long as the longest allows.
      plan.learn(count, count * 10, false);
      ++windows;
    }
    EXPECT_EQ(at, 17 + n) << n;
    EXPECT_LE(windows, int(n / 700000) + 2);
  }
}

TEST(WindowPlan, WindowsFollowWhatTheyHeldALeaf) {
  WindowPlan plan(0, uint64_t(1) << 40, kSlot, 240, UINT64_MAX);
  uint64_t first = 0, count = 0;
  plan.next(&first, &count);
  EXPECT_EQ(count, kSlot / 240);  // the first estimate
  // A window that held 60 bytes a leaf: windows sized for 60 and the margin.
  plan.learn(count, count * 60, false);
  plan.next(&first, &count);
  EXPECT_GT(count, kSlot / 100);
  EXPECT_LE(count * 60 * 3 / 2, kSlot + count);
  // A costlier one lowers them at once.
  const uint64_t cheap = count;
  plan.learn(count, count * 120, false);
  plan.next(&first, &count);
  EXPECT_LT(count, cheap * 2 / 3);
  // Cheaper ones again raise them a step at a time, not at once.
  const uint64_t costly = count;
  plan.learn(count, count * 60, false);
  plan.next(&first, &count);
  EXPECT_GT(count, costly);
  EXPECT_LT(count, cheap);
  for (int i = 0; i < 40; ++i) {
    plan.learn(count, count * 60, false);
    plan.next(&first, &count);
  }
  EXPECT_GE(count + 16, cheap);
  // One that had to be cut: the next ones at most half as long.
  const uint64_t before_cut = count;
  plan.learn(count, count * 30, true);
  plan.next(&first, &count);
  EXPECT_LE(count, before_cut / 2);
}

TEST(WindowPlan, NeverShorterThanAThousandLeavesBeforeTheEnd) {
  WindowPlan plan(0, 100000, 1 << 20, 240, UINT64_MAX);
  uint64_t first = 0, count = 0;
  plan.next(&first, &count);
  plan.learn(count, uint64_t(1) << 40, true);  // far over
  plan.next(&first, &count);
  EXPECT_EQ(count, 1024u);
}

}  // namespace
}  // namespace weaver
