// Tasks made in order, run on several threads, and written in the order
// they were made, with no thread of its own for the making and writing:
// whichever thread is free writes the oldest tasks if they are done and no
// other thread is writing, else makes the next tasks if none is making,
// else runs a task.  The calling thread is one of the workers.  So
// `threads` threads keep `threads` cores busy, where a writer beside them
// would make one more thread than cores and push the workers' caches
// around whenever it ran.
//
// make() and write() are each called by one thread at a time, and never
// together unless make_beside_write() allows it; both without the lock
// that workers take tasks under: a slow make() (a read) holds up no
// worker.  At most `in_flight` tasks exist at once (made, running, done or
// being written), and fewer while room() says no; each is one of
// `in_flight` objects used again and again, so a task's buffers keep their
// room from one use to the next.
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace weaver {

template <class Task>
class OrderedRun {
 public:
  using Make = std::function<bool(Task*)>;       // fills in the next task; false: none left
  using Work = std::function<void(int, Task*)>;  // runs a task on worker i (0: the caller)
  using Write = std::function<bool(Task*)>;      // false: stop (tasks not yet written are dropped)
  using Room = std::function<bool()>;            // whether another task may be made now

  OrderedRun(size_t in_flight, Make make, Work work, Write write, Room room = nullptr)
      : tasks_(in_flight),
        make_(std::move(make)),
        work_(std::move(work)),
        write_(std::move(write)),
        room_(std::move(room)) {
    for (Task& t : tasks_) free_.push_back(&t);
  }

  // Lets make() run on one thread while write() runs on another (each
  // still one call at a time), for callers whose make and write share
  // nothing.  Extract's reads took 19 s and its writes 9 s of a 32 s run at
  // 2 Hz: as one role, on one thread at a time, they were most of the wall
  // time, and the other worker waited for buckets 5.5 s.
  void make_beside_write() { beside_ = true; }

  // Runs until every task is written or write() says stop.
  void go(int threads) {
    std::vector<std::thread> pool;
    for (int i = 1; i < threads; ++i) pool.emplace_back([this, i] { serve(i); });
    serve(0);
    for (auto& t : pool) t.join();
  }

 private:
  struct Slot {
    Task* task;
    bool done;
  };

  // Each thread writes the oldest tasks when they are done, else makes
  // tasks into free objects, else runs a task, else waits for one of
  // these.
  void serve(int worker) {
    std::unique_lock<std::mutex> lock(mu_);
    while (true) {
      // (flight_ is empty for a moment, with more to make, while its last
      // task is written and the next made.)
      cv_.wait(lock, [&] {
        return stopped_ || can_write() || can_make() || !ready_.empty() || finished();
      });
      if (stopped_) break;
      if (can_write()) {
        write_done(lock);
      } else if (can_make()) {
        fill(lock);
      } else if (!ready_.empty()) {
        Task* t = ready_.front();
        ready_.pop_front();
        lock.unlock();
        work_(worker, t);
        lock.lock();
        for (Slot& s : flight_) {
          if (s.task == t) s.done = true;
        }
      } else {
        break;  // all written
      }
    }
    cv_.notify_all();
  }

  bool finished() const { return made_all_ && flight_.empty(); }
  bool can_write() const {
    return !writing_ && (beside_ || !making_) && !flight_.empty() && flight_.front().done;
  }
  // room() is asked only while some task is in flight: with none, one is
  // made.
  bool may_make() const {
    return !made_all_ && !free_.empty() && (!room_ || flight_.empty() || room_());
  }
  bool can_make() const { return !making_ && (beside_ || !writing_) && may_make(); }

  // Writes the oldest tasks while they are done, the lock released while
  // each is written (other workers go on taking tasks meanwhile).  Each
  // object a write frees is made into at once: by another thread beside
  // this one's next write, or (one role) by this thread before it, so that
  // a run of writes does not leave the other workers without tasks.
  void write_done(std::unique_lock<std::mutex>& lock) {
    writing_ = true;
    while (!stopped_ && !flight_.empty() && flight_.front().done) {
      Task* head = flight_.front().task;
      flight_.pop_front();
      lock.unlock();
      const bool go_on = write_(head);
      lock.lock();
      free_.push_back(head);
      if (!go_on) stopped_ = true;
      if (beside_) {
        cv_.notify_all();
      } else {
        fill(lock);
      }
    }
    writing_ = false;
    cv_.notify_all();
  }

  // Makes tasks into the free objects while room() allows, until none is
  // left to make; the lock released while each is made.
  void fill(std::unique_lock<std::mutex>& lock) {
    making_ = true;
    while (!stopped_ && may_make()) {
      Task* t = free_.back();
      free_.pop_back();
      lock.unlock();
      const bool made = make_(t);
      lock.lock();
      if (!made) {
        free_.push_back(t);
        made_all_ = true;
        break;
      }
      flight_.push_back({t, false});
      ready_.push_back(t);
      cv_.notify_one();
    }
    making_ = false;
    cv_.notify_all();
  }

  std::vector<Task> tasks_;
  Make make_;
  Work work_;
  Write write_;
  Room room_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<Slot> flight_;  // made and not yet written, in order
  std::deque<Task*> ready_;  // made and not yet taken
  std::vector<Task*> free_;
  bool beside_ = false;  // make_beside_write()
  bool writing_ = false, making_ = false, stopped_ = false, made_all_ = false;
};

}  // namespace weaver
