// Tasks made in order, run on several threads, and written in the order
// they were made, with no thread of its own for the making and writing:
// whichever thread finishes a task finds whether the oldest ones are done
// and, if no other thread holds that part, writes them and makes the next
// tasks.  The calling thread is one of the workers.  So `threads` threads
// keep `threads` cores busy, where a writer beside them would make one
// more thread than cores and push the workers' caches around whenever it
// ran.
//
// make() and write() are called by one thread at a time, never together,
// and without the lock that workers take tasks under: a slow make() (a
// read) holds up no worker.  At most `in_flight` tasks exist at once
// (made, running, done or being written), and fewer while room() says no;
// each is one of `in_flight` objects used again and again, so a task's
// buffers keep their room from one use to the next.
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

  // Runs until every task is written or write() says stop.
  void go(int threads) {
    // The other workers start first and take tasks as the first ones are
    // made: making them all before starting (16 reads at 2 threads) left the
    // second core idle for a fifth of a 1M-leaf extract.
    std::vector<std::thread> pool;
    for (int i = 1; i < threads; ++i) pool.emplace_back([this, i] { serve(i); });
    {
      std::unique_lock<std::mutex> lock(mu_);
      writing_ = true;  // no worker writes (or makes) while this fills
      fill(lock);
      write_done(lock);  // what finished meanwhile; clears writing_
    }
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
      // (flight_ is empty for a moment, with more to make, while its last
      // task is written and the next made.)
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
    }
    cv_.notify_all();
  }

  // Writes the oldest tasks while they are done, and makes tasks into the
  // objects they free; the lock released while each is written or made
  // (other workers go on taking tasks meanwhile).
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
      fill(lock);
    }
    writing_ = false;
    cv_.notify_all();
  }

  // Makes tasks into the free objects while room() allows (asked only
  // while some task is in flight: with none, one is made), until none is
  // left to make.  Called by the thread that writes, or by go() alone.
  void fill(std::unique_lock<std::mutex>& lock) {
    while (!made_all_ && !stopped_ && !free_.empty()) {
      if (room_ && !flight_.empty() && !room_()) break;
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
  bool writing_ = false, stopped_ = false, made_all_ = false;
};

}  // namespace weaver
