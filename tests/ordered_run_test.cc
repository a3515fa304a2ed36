// util/ordered_run.h: tasks run on several threads are written in the order
// they were made, each once, by one thread at a time (never while one is
// made, unless make_beside_write() allows it), with never more than
// `in_flight` of them alive, nor more than room() allows; a stop writes
// nothing after it.
#include "util/ordered_run.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <random>
#include <thread>

namespace weaver {
namespace {

struct Task {
  int index = -1;
  int value = 0;
  std::thread::id ran_on;
};

// Work of uneven length, so that later tasks often finish first.
void uneven_work(Task* t) {
  std::mt19937 rng(t->index);
  std::this_thread::sleep_for(std::chrono::microseconds(rng() % 400));
  t->value = t->index * 7 + 1;
  t->ran_on = std::this_thread::get_id();
}

struct TaskOutcome {
  std::vector<int> written;
  int most_alive = 0;
  bool overlapping_writes = false;  // two writes, two makes, or (unless beside) one of each
  bool make_beside_write = false;   // a make seen running while a task was written
  int wrong_values = 0;
  std::vector<std::thread::id> threads;
};

// `tasks` tasks on `threads` threads, `in_flight` at once (and at most
// `room` alive, if given); stops after `stop_after` writes (or never).
// `tasks` tasks on `threads` threads, `in_flight` at once (and at most
// `room` alive, if given); stops after `stop_after` writes (or never).
// beside: make_beside_write(), and each write waits (up to half a second)
// for a make to run beside it until one has.
TaskOutcome run(int tasks, int threads, size_t in_flight, int stop_after = -1, int room = 0,
                bool beside = false) {
  TaskOutcome o;
  int made = 0;
  std::atomic<int> alive{0}, makers{0}, writers{0};
  std::atomic<bool> seen{false};
  // A make or write begins: no other of its kind runs, nor of the other
  // kind unless beside.
  auto begin = [&](std::atomic<int>& mine, std::atomic<int>& other) {
    if (++mine > 1 || (!beside && other > 0)) o.overlapping_writes = true;
  };
  OrderedRun<Task> r(
      in_flight,
      [&](Task* t) {
        begin(makers, writers);
        std::this_thread::sleep_for(std::chrono::microseconds(50));  // a slow make
        const bool more = made < tasks;
        if (more) {
          t->index = made++;
          o.most_alive = std::max(o.most_alive, ++alive);
        }
        --makers;
        return more;
      },
      [&](int, Task* t) { uneven_work(t); },
      [&](Task* t) {
        begin(writers, makers);
        const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(500);
        while (beside && !seen && std::chrono::steady_clock::now() < until) {
          if (makers > 0) seen = true;
          std::this_thread::yield();
        }
        o.written.push_back(t->index);
        if (t->value != t->index * 7 + 1) ++o.wrong_values;
        o.threads.push_back(t->ran_on);
        --alive;
        --writers;
        return int(o.written.size()) != stop_after;
      },
      room > 0 ? OrderedRun<Task>::Room([&] { return alive < room; }) : nullptr);
  if (beside) r.make_beside_write();
  r.go(threads);
  o.make_beside_write = seen;
  return o;
}

TEST(OrderedRunThreads, WritesEveryTaskOnceInOrder) {
  for (int threads : {1, 2, 3, 4}) {
    for (size_t in_flight : {1, 2, 5, 8}) {
      const TaskOutcome o = run(60, threads, in_flight);
      ASSERT_EQ(o.written.size(), 60u) << threads << " threads, " << in_flight << " in flight";
      for (int i = 0; i < 60; ++i) EXPECT_EQ(o.written[i], i);
      EXPECT_EQ(o.wrong_values, 0);
      EXPECT_FALSE(o.overlapping_writes);
      EXPECT_LE(o.most_alive, int(in_flight));
    }
  }
}

TEST(OrderedRunThreads, TheCallerIsAWorkerAndTheOthersShareTheWork) {
  const TaskOutcome alone = run(20, 1, 4);
  for (const auto& id : alone.threads) EXPECT_EQ(id, std::this_thread::get_id());
  const TaskOutcome shared = run(200, 3, 6);
  std::vector<std::thread::id> seen;
  for (const auto& id : shared.threads) {
    if (std::find(seen.begin(), seen.end(), id) == seen.end()) seen.push_back(id);
  }
  EXPECT_GE(seen.size(), 2u);  // 200 uneven tasks: one thread does not take them all
}

TEST(OrderedRunThreads, NoMoreTasksAliveThanRoomAllows) {
  for (int threads : {1, 2, 3}) {
    const TaskOutcome o = run(50, threads, 8, -1, 2);
    ASSERT_EQ(o.written.size(), 50u) << threads << " threads";
    for (int i = 0; i < 50; ++i) EXPECT_EQ(o.written[i], i);
    EXPECT_LE(o.most_alive, 2);
    EXPECT_FALSE(o.overlapping_writes);
  }
}

TEST(OrderedRunThreads, AStopWritesNothingAfterIt) {
  for (int threads : {1, 2, 4}) {
    const TaskOutcome o = run(100, threads, 6, 13);
    ASSERT_EQ(o.written.size(), 13u) << threads << " threads";
    for (int i = 0; i < 13; ++i) EXPECT_EQ(o.written[i], i);
  }
}

// Extract's reads and writes: a make runs while a task is written, and
// still no two makes or two writes run at once, and every task is written
// once in order.
TEST(OrderedRunThreads, MakesBesideWritesWhereAllowed) {
  for (int threads : {2, 3}) {
    const TaskOutcome o = run(40, threads, 4, -1, 0, true);
    ASSERT_EQ(o.written.size(), 40u) << threads << " threads";
    for (int i = 0; i < 40; ++i) EXPECT_EQ(o.written[i], i);
    EXPECT_EQ(o.wrong_values, 0);
    EXPECT_FALSE(o.overlapping_writes);
    EXPECT_TRUE(o.make_beside_write);
  }
  const TaskOutcome stopped = run(100, 2, 6, 13, 0, true);
  ASSERT_EQ(stopped.written.size(), 13u);
  for (int i = 0; i < 13; ++i) EXPECT_EQ(stopped.written[i], i);
}

TEST(OrderedRunThreads, NoTasksWritesNothing) {
  for (int threads : {1, 3}) EXPECT_TRUE(run(0, threads, 4).written.empty());
}

}  // namespace
}  // namespace weaver
