// Tasks made in order, run on several threads, and written in the order
// they were made, with no thread of its own for the writing: whichever
// thread finishes a task finds whether the oldest ones are done and, if
// no other thread is writing, writes them.  The calling thread is one of
// the workers.  So `threads` threads keep `threads` cores busy, where a
// writer beside them would make one more thread than cores and push the
// workers' caches around whenever it ran.
//
// At most `in_flight` tasks exist at once (made, running, done or being
// written); each is one of `in_flight` objects used again and again, so a
// task's buffers keep their room from one use to the next.
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

  OrderedRun(size_t in_flight, Make make, Work work, Write write)
      : tasks_(in_flight),
        make_(std::move(make)),
        work_(std::move(work)),
        write_(std::move(write)) {
    for (Task& t : tasks_) free_.push_back(&t);
  }

  // Runs until every task is written or write() says stop.
  void go(int threads) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      fill();
    }
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

  void serve(int worker) {
    std::unique_lock<std::mutex> lock(mu_);
    while (true) {
      // (flight_ is empty for a moment, and no more made, while its last
      // task is written and fill() has yet to run.)
      cv_.wait(lock, [&] { return stopped_ || !ready_.empty() || (made_all_ && flight_.empty()); });
      if (stopped_ || ready_.empty()) break;  // stopped, or all written
      Task* t = ready_.front();
      ready_.pop_front();
      lock.unlock();
      work_(worker, t);
      lock.lock();
      for (Slot& s : flight_) {
        if (s.task == t) s.done = true;
      }
      if (!writing_) write_done(lock);
      cv_.notify_all();
    }
    cv_.notify_all();
  }

  // Writes the oldest tasks while they are done, the lock released while
  // each is written (other workers go on taking tasks meanwhile).
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
      fill();
      cv_.notify_all();
    }
    writing_ = false;
  }

  // Makes tasks into the free objects, until none is left to make.
  void fill() {
    while (!made_all_ && !stopped_ && !free_.empty()) {
      Task* t = free_.back();
      if (!make_(t)) {
        made_all_ = true;
        break;
      }
      free_.pop_back();
      flight_.push_back({t, false});
      ready_.push_back(t);
    }
  }

  std::vector<Task> tasks_;
  Make make_;
  Work work_;
  Write write_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<Slot> flight_;  // made and not yet written, in order
  std::deque<Task*> ready_;  // made and not yet taken
  std::vector<Task*> free_;
  bool writing_ = false, stopped_ = false, made_all_ = false;
};

}  // namespace weaver
