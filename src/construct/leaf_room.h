// How many leaves a subtree's visit may hold: its own room, and more taken
// from a pool that the subtrees in flight share.
//
// The subtrees in flight may hold, together, what the budget's share for
// them allows.  Most hold a small part of an even share, but a subtree
// taken whole (construct.cc) may hold many times its estimate (at 2 Hz the
// basin's soft inclusions, which the estimate's samples miss, put up to
// 981K leaves in one estimated at 64K).  With a fixed share each, such a
// subtree passed it and was descended again as its 8 children: 472 of
// them at 2 Hz, which cost more than whole subtrees saved.  So each
// subtree owns half an even share, and takes more from the pool of the
// other halves while it lasts, up to a bound; a subtree that finds the
// pool empty is visited again as its children, as one past a fixed share
// was, and its own half guarantees that the oldest subtree (the one the
// writer waits for) always completes once small enough.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace weaver {

// Leaves the subtrees in flight may take beyond their own rooms.
class LeafPool {
 public:
  explicit LeafPool(uint64_t spare) : spare_(spare) {}
  // Takes n leaves if the pool has them.
  bool take(uint64_t n) {
    uint64_t have = spare_.load(std::memory_order_relaxed);
    while (have >= n) {
      if (spare_.compare_exchange_weak(have, have - n, std::memory_order_relaxed)) return true;
    }
    return false;
  }
  void give(uint64_t n) { spare_.fetch_add(n, std::memory_order_relaxed); }
  uint64_t spare() const { return spare_.load(std::memory_order_relaxed); }

 private:
  std::atomic<uint64_t> spare_;
};

// One subtree's room: `own` leaves always, up to `most` while the pool
// lends them (no pool: `own` alone).  What it took it keeps until
// give_back() (subtree_slots.h: once its leaves are written).
class LeafRoom {
 public:
  LeafRoom() = default;
  LeafRoom(size_t own, size_t most, LeafPool* pool)
      : own_(own), most_(pool ? std::max(own, most) : own), room_(own), pool_(pool) {}

  // Whether the subtree may hold n leaves (taken from the pool past its own
  // room: half its room again at a time where the pool has it, else n, so
  // that the pool is asked rarely and the leaves' vectors, reserved at the
  // room, move a few times, not once for every eighth of the own room).
  bool allows(size_t n) {
    if (n <= room_) return true;
    if (n > most_) return false;
    size_t want = std::min(most_, std::max(n, room_ + room_ / 2));  // room_ >= own_
    if (!pool_->take(want - room_)) {
      if (want == n || !pool_->take(n - room_)) return false;
      want = n;
    }
    room_ = want;
    return true;
  }
  // The leaves it may hold without asking the pool.
  size_t room() const { return room_; }
  // What it took from the pool, returned.
  void give_back() {
    if (room_ > own_) pool_->give(room_ - own_);
    room_ = own_;
  }
  // The leaves it took from the pool.
  size_t taken() const { return room_ - own_; }

 private:
  size_t own_ = 0, most_ = 0, room_ = 0;
  LeafPool* pool_ = nullptr;
};

}  // namespace weaver
