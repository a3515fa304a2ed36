// A subtree's leaf room (construct/leaf_room.h): its own leaves always,
// more from the shared pool up to its most, all of it given back.
#include "construct/leaf_room.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

namespace weaver {
namespace {

TEST(LeafRoom, WithoutAPoolAllowsItsOwnLeavesAlone) {
  LeafRoom room(100, 400, nullptr);
  EXPECT_TRUE(room.allows(100));
  EXPECT_FALSE(room.allows(101));
  EXPECT_EQ(room.taken(), 0u);
}

TEST(LeafRoom, TakesFromThePoolUpToItsMostAndGivesItBack) {
  LeafPool pool(1000);
  LeafRoom room(64, 256, &pool);
  EXPECT_TRUE(room.allows(64));
  EXPECT_EQ(pool.spare(), 1000u);  // its own room takes nothing
  EXPECT_TRUE(room.allows(65));    // half its room again at a time
  EXPECT_EQ(room.taken(), 32u);
  EXPECT_EQ(room.room(), 96u);
  EXPECT_EQ(pool.spare(), 968u);
  EXPECT_TRUE(room.allows(96));  // within the room: nothing more taken
  EXPECT_EQ(room.taken(), 32u);
  EXPECT_TRUE(room.allows(200));
  EXPECT_EQ(room.taken(), 136u);
  EXPECT_TRUE(room.allows(256));
  EXPECT_FALSE(room.allows(257));  // past its most, whatever the pool has
  EXPECT_EQ(pool.spare(), 1000u - 192);
  room.give_back();
  EXPECT_EQ(room.taken(), 0u);
  EXPECT_EQ(pool.spare(), 1000u);
}

// Where the pool has less than half the room again, it lends just what the
// subtree asks.
TEST(LeafRoom, APoolShortOfAStepLendsWhatIsAsked) {
  LeafPool pool(10);
  LeafRoom room(64, 256, &pool);
  EXPECT_TRUE(room.allows(70));
  EXPECT_EQ(room.room(), 70u);
  EXPECT_EQ(pool.spare(), 4u);
  EXPECT_FALSE(room.allows(75));
  EXPECT_EQ(room.room(), 70u);
}

TEST(LeafRoom, AnEmptyPoolRefusesAndRoomsShareIt) {
  LeafPool pool(100);
  LeafRoom a(50, 1000, &pool), b(50, 1000, &pool);
  EXPECT_TRUE(a.allows(150));  // all the pool
  EXPECT_EQ(pool.spare(), 0u);
  EXPECT_TRUE(b.allows(50));
  EXPECT_FALSE(b.allows(51));  // the pool is a's
  a.give_back();
  EXPECT_TRUE(b.allows(51));
}

// Threads taking and giving back at once never hold more than the pool
// had, and at the end it holds all it began with.
TEST(LeafRoom, ThreadsNeverTakeMoreThanThePoolHolds) {
  LeafPool pool(1000);
  std::atomic<int64_t> held{0};
  std::atomic<bool> over{false};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (int i = 0; i < 20000; ++i) {
        LeafRoom room(8, 8 + 400, &pool);
        if (room.allows(8 + 1 + (i * 37 + t) % 400)) {
          const int64_t taken = static_cast<int64_t>(room.taken());
          if (held.fetch_add(taken) + taken > 1000) over = true;
          held.fetch_sub(taken);
        }
        room.give_back();
      }
    });
  }
  for (auto& th : threads) th.join();
  EXPECT_FALSE(over.load());
  EXPECT_EQ(pool.spare(), 1000u);
}

}  // namespace
}  // namespace weaver
