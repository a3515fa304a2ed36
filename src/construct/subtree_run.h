// Construct's subtrees visited on several threads and appended in Z-order,
// with no writer thread of its own: whichever thread is free appends the
// oldest subtrees if they are visited and no other thread is appending,
// else visits the next one (as util/ordered_run.h does, which cannot put a
// subtree's children in its place).  A subtree past its room is replaced
// by its eight children, first in line.
//
// A writer thread beside the workers (as construct had) made three threads
// on two cores: the writer got two thirds of a core while all three ran,
// fell behind, and the workers waited 8.5 s of a 40 s 2 Hz construct for
// subtrees to visit (the window full of visited subtrees not yet written).
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>

#include "construct/subtree_slots.h"
#include "schema/octant.h"
#include "schema/status.h"

namespace weaver {

class SubtreeRun {
 public:
  using Next = std::function<bool(Octant*)>;         // the next subtree's root; false: none left
  using Visit = std::function<void(int, Slot*)>;     // visits a subtree on thread i (0: the caller)
  using Write = std::function<Status(const Slot&)>;  // appends a visited subtree's leaves
  using Over = std::function<void()>;                // a subtree past its room, replaced

  // Up to `window` subtrees in flight (visited or not, not yet written).
  SubtreeRun(size_t window, SubtreeSlots& slots, Next next, Visit visit, Write write, Over over);

  // Runs on `threads` threads (this one among them) until every subtree is
  // written or a write fails; returns the failure.
  Status go(int threads);

 private:
  void serve(int worker);
  // Under the lock: the next subtrees into the window.
  void refill();
  bool can_write() const;
  bool finished() const { return listed_all_ && in_flight_.empty(); }
  // Appends the oldest subtrees while they are visited (the lock released
  // while each is appended), and replaces one past its room by its children.
  void write_done(std::unique_lock<std::mutex>& lock);

  const size_t window_;
  SubtreeSlots& slots_;
  Next next_;
  Visit visit_;
  Write write_;
  Over over_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::unique_ptr<Slot>> in_flight_;  // Z-order
  std::deque<Slot*> queued_;                     // not yet visited, the next first
  bool writing_ = false, listed_all_ = false, stopped_ = false;
  Status status_;
};

}  // namespace weaver
