// The queue between a stage's main thread, which hands out tasks and
// consumes their results in order, and its worker threads.  Task is any
// type with a `bool done` member; a worker fills in the task, then calls
// finish(), which publishes everything it wrote to the thread that waits.
#pragma once

#include <condition_variable>
#include <deque>
#include <mutex>

namespace weaver {

template <class Task>
class WorkQueue {
 public:
  // Adds a task at the back, or at the front (to be taken next: the
  // consumer is waiting for it).
  void push(Task* t, bool front = false) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (front) {
        queue_.push_front(t);
      } else {
        queue_.push_back(t);
      }
    }
    work_.notify_one();
  }
  // The next task; null once stopped.
  Task* pop() {
    std::unique_lock<std::mutex> lock(mu_);
    work_.wait(lock, [&] { return stopped_ || !queue_.empty(); });
    if (stopped_) return nullptr;
    Task* t = queue_.front();
    queue_.pop_front();
    return t;
  }
  void finish(Task* t) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      t->done = true;
    }
    done_.notify_all();
  }
  void wait_done(Task* t) {
    std::unique_lock<std::mutex> lock(mu_);
    done_.wait(lock, [&] { return t->done; });
  }
  // Wakes the workers to return null from pop().  Tasks still queued are
  // dropped: wait for the ones running first.
  void stop() {
    {
      std::lock_guard<std::mutex> lock(mu_);
      stopped_ = true;
    }
    work_.notify_all();
  }

 private:
  std::mutex mu_;
  std::condition_variable work_, done_;
  std::deque<Task*> queue_;
  bool stopped_ = false;
};

}  // namespace weaver
