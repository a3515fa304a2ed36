// How long balance's windows are.  The first ones are sized by a fixed
// estimate of what a leaf costs a window (its key and payload, about four
// times that for its refinement, and the ripple's work); those that follow,
// by what the windows written so far held a leaf, with a margin.  On the
// 1 Hz basin a window holds 73 to 92 bytes a leaf, a third of the fixed
// estimate, so windows grow about twofold with the margin (68 windows on
// one thread where there were 133); where the refinement grows many times
// over (random refinement), they shrink.  A
// window that does not fit is cut in two all the same: sizing costs time,
// never the table.
#pragma once

#include <algorithm>
#include <cstdint>

namespace weaver {

class WindowPlan {
 public:
  // Windows over leaves [lo, lo + n), each within `slot_bytes`, of at most
  // `longest` leaves; `first_per_leaf` bytes a leaf until windows are
  // measured.
  WindowPlan(uint64_t lo, uint64_t n, uint64_t slot_bytes, uint64_t first_per_leaf,
             uint64_t longest)
      : next_(lo),
        end_(lo + n),
        slot_(slot_bytes),
        per_leaf_(std::max<uint64_t>(first_per_leaf, 1)),
        longest_(std::max<uint64_t>(longest, 1)) {}

  bool more() const { return next_ < end_; }

  // The next window's first leaf and length.
  void next(uint64_t* first, uint64_t* count) {
    const uint64_t sized = std::max<uint64_t>(kShortest, slot_ / per_leaf_);
    *first = next_;
    *count = std::min({sized, longest_, end_ - next_});
    next_ += *count;
  }

  // A written window of `count` leaves that held at most `peak` bytes at
  // once, or that had to be cut (then a leaf costs more than its share).
  // One costly window lowers the estimate at once; cheap ones raise it a
  // quarter of the way at a time, so a costly stretch of the table is
  // not met by windows sized for the cheap one before it.
  void learn(uint64_t count, uint64_t peak, bool cut) {
    if (count == 0) return;
    uint64_t seen = peak * kMarginPercent / 100 / count + 1;
    if (cut) seen = std::max(seen, 2 * slot_ / count + 1);
    if (!measured_ || seen > per_leaf_) {
      per_leaf_ = seen;
    } else if (seen < per_leaf_) {
      per_leaf_ -= std::max<uint64_t>(1, (per_leaf_ - seen) / 4);
    }
    measured_ = true;
  }

  uint64_t per_leaf() const { return per_leaf_; }

 private:
  static constexpr uint64_t kShortest = 1024;
  static constexpr uint64_t kMarginPercent = 150;
  uint64_t next_, end_;
  const uint64_t slot_;
  uint64_t per_leaf_;
  const uint64_t longest_;
  bool measured_ = false;
};

}  // namespace weaver
