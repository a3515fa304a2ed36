// A worker of balance in windows (window_balance.h): reads a window's
// leaves through its own handle on the table, collects its insulation
// layer, ripples them and refines its own leaves, cutting the window in
// two while it does not fit its share of memory; or, given the one window
// of every leaf, refines a block of it.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "balance/balance.h"
#include "balance/forward_floor.h"
#include "balance/refinement.h"
#include "balance/window_balance.h"
#include "schema/status.h"
#include "storage/btree.h"
#include "util/local_ripple.h"
#include "util/recent_keys.h"

namespace weaver {

// One window on its way from a worker to the table: the `count` leaves
// whose keys lie in [from, to), and their refinement.
struct Window {
  uint64_t first = 0;  // its first leaf's index (in the table, or in the one window)
  uint64_t count = 0;
  uint64_t from = 0, to = 0;
  std::vector<uint64_t> keys;  // the refinement
  std::vector<std::byte> payloads;
  LevelCounts levels{};
  uint64_t split = 0, created = 0, layer = 0;
  uint64_t peak = 0;   // the most bytes its worker held at once for it
  bool cut = false;    // it did not fit whole, and went in parts
  bool fitted = true;  // false: it gave up (too short to cut, or outweighed by its layer)
  Status status;

  // Ready to be made again, its refinement's buffers kept: allocated
  // afresh, a refinement of tens of MB is mapped and faulted in page by
  // page (at 1 Hz on one thread, 2 s of system time).
  void reset() {
    keys.clear();
    payloads.clear();
    levels = {};
    split = created = layer = peak = 0;
    cut = false;
    fitted = true;
    status = Status::Ok();
  }
};

// One window of every leaf, read and rippled once (the ripple's levels
// shared between the threads); its refinement then goes in blocks of
// consecutive leaves, on the workers as windows go.
struct WholeTable {
  std::vector<uint64_t> keys, created;
  std::vector<std::byte> payloads;

  uint64_t bytes() const {
    return (keys.capacity() + created.capacity()) * sizeof(uint64_t) + payloads.capacity();
  }
};

// `count` leaves from the first at or after key `from` into *keys and
// *payloads; Corruption if the table holds fewer (or, asked for all of
// them, more).
Status read_leaves(BTree& leaves, uint64_t from, uint64_t count, bool all,
                   std::vector<uint64_t>* keys, std::vector<std::byte>* payloads);

// A worker: one a thread, each with its own handle on the table.
class WindowWorker {
 public:
  WindowWorker(BTree& leaves, uint64_t bytes, const FillPayload& fill, const WindowOptions& o)
      : leaves_(leaves),
        bytes_(bytes),
        payload_(leaves.payload_size()),
        fill_(fill),
        layer_limit_(o.layer_limit),
        layer_window_(o.layer_window),
        least_cut_(o.least_cut) {}

  // Set by any worker whose window gives up: the others stop too.
  void share_giving_up(std::atomic<bool>* flag) { given_up_ = flag; }
  // The one window: windows are then blocks of its leaves, to refine.
  void share_whole(const WholeTable* whole) { whole_ = whole; }

  // Balances w (or, given the one window, refines its block), leaving in
  // w its refinement or that it gave up; gives up at once if another
  // worker has.
  void run(Window* w);

 private:
  // w gives up, and tells the other workers.
  void give_up(Window* w);

  // w's keys: from its first leaf's to the next window's first leaf's (0
  // before the first leaf, none past the last).
  Status bounds(Window* w);

  Status read(const Window& w);

  // Own leaves [i0, i1), keys in [from, to), into w's refinement.
  Status balance(size_t i0, size_t i1, uint64_t from, uint64_t to, Window* w);

  // What the window holds: its own leaves, what it asked for and their
  // sort, the layer, the local set, the ripple's map, asks and what it
  // created, and a refinement of out_leaves.  As allocated, whether it
  // fits (the worker's vectors keep their room from window to window);
  // as used, what this window costs a leaf (the room kept from longer
  // windows before it aside: sized by it, windows would shrink window
  // after window).  The ripple's bytes are as allocated either way.
  uint64_t held(uint64_t out_leaves, bool allocated = true) const;

  Status try_balance(size_t i0, size_t i1, uint64_t from, uint64_t to, Window* w, bool* fits);

  // The leaves outside [from, to) that meet the block of an own leaf, in
  // key order, into layer_ (those before the window first).  An own leaf
  // whose block lies inside the coarsest octant of the window holding it
  // asks for nothing.
  Status collect_layer(size_t i0, size_t i1, uint64_t from, uint64_t to, bool* fits);

  // asked_ sorted, once each, keeping the outermost of nested octants (an
  // ancestor's key comes first).
  void compact_asked();

  // The leaves meeting [lo, hi) (the one holding lo, and those with keys in
  // it) outside [from, to), into layer_.  Calls come in key order.
  Status collect_range(ForwardFloor& f, uint64_t lo, uint64_t hi, uint64_t from, uint64_t to);

  // The n leaves at keys (their payloads at payloads) split just enough to
  // resolve `created`, appended to w's refinement; undone if the
  // refinement outgrows the memory.  from and to bound their keys.
  Status refine(const uint64_t* keys, const std::byte* payloads, size_t n,
                const std::vector<uint64_t>& created, uint64_t from, uint64_t to, Window* w,
                bool* fits);

  BTree& leaves_;
  const uint64_t bytes_;
  const size_t payload_;
  const FillPayload& fill_;
  const double layer_limit_;
  const uint64_t layer_window_;  // whole windows this long give up when outweighed
  const uint64_t least_cut_;     // windows this short that do not fit give up
  bool outweighed_ = false;      // a whole window's layer outweighed it: the run gives up
  std::atomic<bool>* given_up_ = nullptr;
  const WholeTable* whole_ = nullptr;
  std::vector<uint64_t> keys_;  // the window's own leaves
  std::vector<std::byte> payloads_;
  std::vector<uint64_t> asked_;  // octants whose leaves the layer holds
  RecentKeys<10> recent_;        // the octants asked last
  std::vector<uint64_t> scratch_;
  std::vector<uint64_t> layer_;  // before the window, then after it
  size_t layer_before_ = 0;
  std::vector<uint64_t> local_, created_;
  LocalRipple ripple_;
};

}  // namespace weaver
