#include "construct/subtree_run.h"

#include <thread>
#include <utility>
#include <vector>

namespace weaver {

SubtreeRun::SubtreeRun(size_t window, SubtreeSlots& slots, Next next, Visit visit, Write write,
                       Over over)
    : window_(window),
      slots_(slots),
      next_(std::move(next)),
      visit_(std::move(visit)),
      write_(std::move(write)),
      over_(std::move(over)) {}

Status SubtreeRun::go(int threads) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    refill();
  }
  std::vector<std::thread> pool;
  for (int i = 1; i < threads; ++i) pool.emplace_back([this, i] { serve(i); });
  serve(0);
  for (auto& t : pool) t.join();
  // (Subtrees still in flight after a failure were visited or dropped:
  // no thread holds one now.)
  return status_;
}

void SubtreeRun::refill() {
  Octant root;
  while (!listed_all_ && in_flight_.size() < window_) {
    if (!next_(&root)) {
      listed_all_ = true;
      break;
    }
    in_flight_.push_back(slots_.take(root));
    queued_.push_back(in_flight_.back().get());
  }
}

bool SubtreeRun::can_write() const {
  return !writing_ && !in_flight_.empty() && in_flight_.front()->done;
}

void SubtreeRun::serve(int worker) {
  std::unique_lock<std::mutex> lock(mu_);
  while (true) {
    cv_.wait(lock, [&] { return stopped_ || can_write() || !queued_.empty() || finished(); });
    if (stopped_) break;
    if (can_write()) {
      write_done(lock);
    } else if (!queued_.empty()) {
      Slot* s = queued_.front();
      queued_.pop_front();
      lock.unlock();
      visit_(worker, s);
      lock.lock();
      s->done = true;
    } else {
      break;  // all written
    }
  }
  cv_.notify_all();
}

void SubtreeRun::write_done(std::unique_lock<std::mutex>& lock) {
  writing_ = true;
  while (!stopped_ && !in_flight_.empty() && in_flight_.front()->done) {
    Slot* head = in_flight_.front().get();
    if (head->leaves.overflow) {
      over_();
      const Octant big = head->root;
      slots_.put(std::move(in_flight_.front()));
      in_flight_.pop_front();
      for (int c = 7; c >= 0; --c) {  // child 0 first
        in_flight_.push_front(slots_.take(octant_child(big, c)));
        queued_.push_front(in_flight_.front().get());
      }
      cv_.notify_all();
      continue;
    }
    lock.unlock();
    const Status st = write_(*head);  // the head stays first: only this thread moves it
    lock.lock();
    slots_.put(std::move(in_flight_.front()));
    in_flight_.pop_front();
    if (!st.ok()) {
      status_ = st;
      stopped_ = true;
      break;
    }
    refill();
    cv_.notify_all();
  }
  writing_ = false;
  cv_.notify_all();
}

}  // namespace weaver
