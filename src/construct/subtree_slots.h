// The subtrees of a construct on their way from the workers to the table,
// each in a slot, and the slots written and waiting to be taken again.
//
// A slot's vectors keep their capacity from one subtree to the next, as far
// as its own room (leaf_room.h): grown afresh for each (reallocated,
// copied, faulted in), a construct takes longer.  They are reserved at
// the own room when made: grown by doubling instead, they could hold twice
// the room, and the copies of each growth freed behind them stayed in the
// allocator (construct from the 100 m model database at --memory 64M on
// two threads peaked at 67,840 and 68,616 KiB; reserved, 66,496 and
// 65,056, the rest of the way under 65,536 made by construct's plan).
// A slot whose subtree took leaves from the pool frees its vectors and
// gives them back once written: kept, they would hold memory the pool
// lends again (so the pool counts all the subtrees' memory).  Kept
// instead, the pool counting them and freeing them where it ran short, the
// 2 Hz construct was no faster (0.924x of the fixed rooms' time against
// 0.919x, separate runs) and peaked at 485 MB against 335 MB.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "construct/descent.h"
#include "construct/leaf_room.h"
#include "schema/octant.h"

namespace weaver {

struct Slot {
  Octant root;
  LeafRoom room;
  SubtreeLeaves leaves;
  uint64_t descended = 0;     // leaves before the balance
  uint64_t air = 0, cut = 0;  // carved: leaves dropped, leaves cut (carve.h)
  bool done = false;          // visited (subtree_run.h)

  // As new, but for its room and the leaves' capacity (visit_subtree
  // clears them).
  void reset();
};

class SubtreeSlots {
 public:
  // Rooms of `own` leaves, each taking up to `most` from a pool of `spare`
  // (none: rooms of `own` alone), for leaves of payload_bytes records.
  SubtreeSlots(size_t own, size_t most, uint64_t spare, size_t payload_bytes);
  SubtreeSlots(const SubtreeSlots&) = delete;
  SubtreeSlots& operator=(const SubtreeSlots&) = delete;

  // A slot for the subtree at root, reset.
  std::unique_ptr<Slot> take(const Octant& root);
  // A slot whose leaves are written or dropped.
  void put(std::unique_ptr<Slot> slot);

 private:
  void reserve_own(SubtreeLeaves* leaves) const;

  LeafPool pool_;
  size_t own_, most_, payload_bytes_;
  bool pooled_;
  std::vector<std::unique_ptr<Slot>> written_;
};

}  // namespace weaver
