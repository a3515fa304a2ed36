#include "construct/subtree_slots.h"

#include <algorithm>
#include <utility>

namespace weaver {

void Slot::reset() {
  SubtreeLeaves kept = std::move(leaves);
  const LeafRoom kept_room = room;
  *this = Slot{};
  leaves = std::move(kept);
  room = kept_room;
}

SubtreeSlots::SubtreeSlots(size_t own, size_t most, uint64_t spare, size_t payload_bytes)
    : pool_(spare), own_(own), most_(most), payload_bytes_(payload_bytes), pooled_(spare > 0) {}

// Room for its own leaves at once (the pages are touched only as leaves
// fill them), so that no subtree within it reallocates and copies.
void SubtreeSlots::reserve_own(SubtreeLeaves* leaves) const {
  leaves->keys.reserve(own_);
  leaves->payloads.reserve(own_ * payload_bytes_);
}

std::unique_ptr<Slot> SubtreeSlots::take(const Octant& root) {
  std::unique_ptr<Slot> slot;
  if (written_.empty()) {
    slot = std::make_unique<Slot>();
    slot->room = LeafRoom(own_, most_, pooled_ ? &pool_ : nullptr);
    reserve_own(&slot->leaves);
  } else {
    slot = std::move(written_.back());
    written_.pop_back();
    slot->reset();
  }
  slot->root = root;
  return slot;
}

void SubtreeSlots::put(std::unique_ptr<Slot> slot) {
  if (slot->room.taken() > 0) {
    slot->leaves = SubtreeLeaves{};
    reserve_own(&slot->leaves);
    slot->room.give_back();
  }
  written_.push_back(std::move(slot));
}

}  // namespace weaver
