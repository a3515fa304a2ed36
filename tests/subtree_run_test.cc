// construct/subtree_run.h: subtrees visited on several threads are written
// in Z-order, one write at a time, each once; one past its room is
// replaced by its eight children, first in line; a failed write stops the
// run and is its status.
#include "construct/subtree_run.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <random>
#include <thread>
#include <vector>

#include "schema/octant.h"

namespace weaver {
namespace {

// Visits "overflow" where the root is one of `big` (but not its children),
// after a pause of uneven length.
struct Outcome {
  std::vector<uint64_t> written;
  uint64_t over = 0;
  bool overlapping_writes = false;
  Status status;
};

Outcome run(const std::vector<Octant>& roots, const std::vector<Octant>& big, int threads,
            size_t window, int fail_at = -1) {
  Outcome o;
  SubtreeSlots slots(64, 64, 0, 12);
  size_t next = 0;
  std::atomic<int> writers{0};
  SubtreeRun r(
      window, slots,
      [&](Octant* root) {
        if (next == roots.size()) return false;
        *root = roots[next++];
        return true;
      },
      [&](int, Slot* s) {
        std::mt19937 rng(static_cast<unsigned>(octant_key(s->root)));
        std::this_thread::sleep_for(std::chrono::microseconds(rng() % 300));
        s->leaves.clear();
        for (const Octant& b : big) s->leaves.overflow |= b == s->root;
        if (!s->leaves.overflow) s->leaves.keys.push_back(octant_key(s->root));
      },
      [&](const Slot& s) {
        if (++writers > 1) o.overlapping_writes = true;
        o.written.push_back(s.leaves.keys.at(0));
        --writers;
        return int(o.written.size()) == fail_at ? Status::IOError("disk full") : Status::Ok();
      },
      [&] { ++o.over; });
  o.status = r.go(threads);
  return o;
}

// The octants of level 2 in Z-order (64 of them).
std::vector<Octant> level_two() {
  std::vector<Octant> out;
  for (int a = 0; a < 8; ++a) {
    for (int b = 0; b < 8; ++b) out.push_back(octant_child(octant_child(Octant{}, a), b));
  }
  return out;
}

TEST(SubtreeRunThreads, WritesInZOrderWithOverflowsReplacedByTheirChildren) {
  const std::vector<Octant> roots = level_two();
  const std::vector<Octant> big = {roots[0], roots[5], roots[63],
                                   octant_child(roots[5], 3)};  // a child overflows too
  std::vector<uint64_t> want;
  for (const Octant& r : roots) {
    if (!(r == roots[0] || r == roots[5] || r == roots[63])) {
      want.push_back(octant_key(r));
      continue;
    }
    for (int c = 0; c < 8; ++c) {
      const Octant child = octant_child(r, c);
      if (child == big[3]) {
        for (int g = 0; g < 8; ++g) want.push_back(octant_key(octant_child(child, g)));
      } else {
        want.push_back(octant_key(child));
      }
    }
  }
  for (int threads : {1, 2, 3}) {
    for (size_t window : {1, 4, 16}) {
      const Outcome o = run(roots, big, threads, window);
      EXPECT_TRUE(o.status.ok());
      EXPECT_EQ(o.written, want) << threads << " threads, window " << window;
      EXPECT_EQ(o.over, 4u);
      EXPECT_FALSE(o.overlapping_writes);
    }
  }
}

TEST(SubtreeRunThreads, AFailedWriteStopsTheRun) {
  for (int threads : {1, 2}) {
    const Outcome o = run(level_two(), {}, threads, 8, 10);
    EXPECT_EQ(o.status.code(), Status::Code::kIOError);
    EXPECT_EQ(o.written.size(), 10u) << threads << " threads";
  }
}

TEST(SubtreeRunThreads, NoSubtreesWritesNothing) {
  const Outcome o = run({}, {}, 2, 8);
  EXPECT_TRUE(o.status.ok());
  EXPECT_TRUE(o.written.empty());
}

// A slot holds its own room's leaves where it was made, and again after
// a subtree that took from the pool was written: its vectors never move
// (no growth copies, no freed copies left behind in the allocator).
TEST(SubtreeSlots, LeavesUpToTheOwnRoomNeverMoveTheVectors) {
  constexpr size_t kOwn = 1000, kBytes = 12;
  SubtreeSlots slots(kOwn, 4 * kOwn, 8 * kOwn, kBytes);
  auto fill = [](Slot* s, size_t n) {
    const uint64_t* keys = nullptr;
    const std::byte* payloads = nullptr;
    bool moved = false;
    for (size_t i = 0; i < n; ++i) {
      if (!s->room.allows(i + 1)) return false;
      s->leaves.keys.push_back(i);
      s->leaves.payloads.resize(s->leaves.payloads.size() + kBytes);
      if (i == 0) keys = s->leaves.keys.data(), payloads = s->leaves.payloads.data();
      moved |= keys != s->leaves.keys.data() || payloads != s->leaves.payloads.data();
    }
    return !moved;
  };
  std::unique_ptr<Slot> s = slots.take(Octant{0, 0, 0, 1});
  EXPECT_TRUE(fill(s.get(), kOwn));
  s->leaves.clear();
  // Past the own room the pool lends leaves, and the vectors grow.
  fill(s.get(), 3 * kOwn);
  ASSERT_GT(s->room.taken(), 0u);
  slots.put(std::move(s));
  s = slots.take(Octant{0, 0, 0, 1});
  EXPECT_TRUE(s->leaves.keys.empty());
  EXPECT_TRUE(fill(s.get(), kOwn));
}

// Past its own room a subtree's vectors grow to the room the pool lends
// (SubtreeLeaves::fit), never to twice the leaves, as doubling would.
TEST(SubtreeSlots, LeavesPastTheOwnRoomHoldTheRoomLentAndNoMore) {
  constexpr size_t kOwn = 1000, kBytes = 12;
  SubtreeSlots slots(kOwn, 4 * kOwn, 8 * kOwn, kBytes);
  std::unique_ptr<Slot> s = slots.take(Octant{0, 0, 0, 1});
  SubtreeLeaves& l = s->leaves;
  size_t grants = 0, last_room = kOwn;
  for (size_t i = 0; i < 4 * kOwn; ++i) {
    ASSERT_TRUE(s->room.allows(i + 1));
    l.fit(s->room.room(), kBytes);
    l.keys.push_back(i);
    l.payloads.resize(l.payloads.size() + kBytes);
    ASSERT_EQ(l.keys.capacity(), s->room.room()) << i;
    ASSERT_EQ(l.payloads.capacity(), s->room.room() * kBytes) << i;
    grants += s->room.room() != last_room;
    last_room = s->room.room();
  }
  // 1000 -> 1500 -> 2250 -> 3375 -> 4000: a few moves, not one an eighth.
  EXPECT_EQ(grants, 4u);
}

}  // namespace
}  // namespace weaver
