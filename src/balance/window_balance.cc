#include "balance/window_balance.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstring>
#include <deque>
#include <memory>
#include <thread>

#include "balance/forward_floor.h"
#include "balance/window_edges.h"
#include "schema/octant.h"
#include "util/local_ripple.h"
#include "util/radix_sort.h"
#include "util/recent_keys.h"
#include "util/resolve_split.h"
#include "util/work_queue.h"

namespace weaver {
namespace {

using window_edges::kCrossing;
using window_edges::kReachable;
using window_edges::neighbours_leaving;
using window_edges::touched_sides;
using window_edges::within;

// One window on its way from a worker to the table: the `count` leaves
// whose keys lie in [from, to), and their refinement.
struct Window {
  uint64_t first = 0;  // a block of the one window: the index of its first leaf
  uint64_t count = 0;
  uint64_t from = 0, to = 0;
  std::vector<uint64_t> keys;  // the refinement
  std::vector<std::byte> payloads;
  LevelCounts levels{};
  uint64_t split = 0, created = 0, layer = 0;
  bool fitted = true;  // false: it gave up (too short to cut, or outweighed by its layer)
  Status status;
  bool done = false;  // set by the worker (WorkQueue)
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

// What one window holds for each leaf (its key, a holder, its share of the
// created octants and the ripple's sort of them, its parent's ask), beside
// its payload; the ripple's measure decides in the end.
constexpr uint64_t kWholeBytesPerLeaf = 64;
constexpr uint64_t kRippleBytesPerLeaf = 160;
// One window's blocks: short enough for several in flight to stay small.
constexpr uint64_t kBlockLeaves = 16384;
// The least room for each leaf of a block in flight (its refinement) that
// the one window leaves after its ripple, or it is not taken.
constexpr uint64_t kBlockBytesPerLeaf = 64;

// A payload row copied (none where the table has no payload).
void copy_bytes(std::byte* to, const std::byte* from, size_t n) {
  if (n > 0) std::memcpy(to, from, n);
}

// `count` leaves from the first at or after key `from` into *keys and
// *payloads; Corruption if the table holds fewer (or, asked for all of
// them, more).
Status read_leaves(BTree& leaves, uint64_t from, uint64_t count, bool all,
                   std::vector<uint64_t>* keys, std::vector<std::byte>* payloads) {
  const size_t payload = leaves.payload_size();
  keys->clear();
  keys->reserve(count);
  payloads->resize(count * payload);
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(leaves.seek_cursor(from, &c));
  for (uint64_t i = 0; i < count && c.valid(); ++i) {
    keys->push_back(c.key());
    copy_bytes(payloads->data() + i * payload, c.payload(), payload);
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  if (keys->size() != count || (all && c.valid())) {
    return Status::Corruption("the octant table changed under balance");
  }
  return Status::Ok();
}

// A worker: reads a window's leaves through its own handle on the table,
// then balances them against their layer, cutting the window in two while
// it does not fit in `bytes`.
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

  void run(Window* w) {
    if (given_up_ != nullptr && given_up_->load()) {
      w->fitted = false;
      return;
    }
    if (whole_ != nullptr) {
      bool fits = false;
      w->status =
          refine(whole_->keys.data() + w->first, whole_->payloads.data() + w->first * payload_,
                 w->count, whole_->created, w->from, w->to, w, &fits);
      if (w->status.ok() && !fits) give_up(w);
      return;
    }
    w->status = read(*w);
    if (w->status.ok()) w->status = balance(0, keys_.size(), w->from, w->to, w);
    if (outweighed_) give_up(w);
  }

 private:
  void give_up(Window* w) {
    w->fitted = false;
    if (given_up_ != nullptr) given_up_->store(true);
  }

  Status read(const Window& w) {
    return read_leaves(leaves_, w.from, w.count, false, &keys_, &payloads_);
  }

  // Own leaves [i0, i1), keys in [from, to), into w's refinement.
  Status balance(size_t i0, size_t i1, uint64_t from, uint64_t to, Window* w) {
    bool fits = false;
    WEAVER_RETURN_IF_ERROR(try_balance(i0, i1, from, to, w, &fits));
    if (fits || outweighed_) return Status::Ok();
    if (i1 - i0 <= least_cut_) {  // short, and still too much: give up
      w->fitted = false;
      return Status::Ok();
    }
    const size_t mid = i0 + (i1 - i0) / 2;
    WEAVER_RETURN_IF_ERROR(balance(i0, mid, from, keys_[mid], w));
    return w->fitted ? balance(mid, i1, keys_[mid], to, w) : Status::Ok();
  }

  // What the window holds: its own leaves, what it asked for, the layer,
  // the local set, the ripple's map, asks and what it created, and the
  // refinement.
  uint64_t held(uint64_t out_leaves) const {
    return keys_.size() * (8 + payload_) + 16 * asked_.size() + 8 * layer_.size() +
           8 * local_.size() + ripple_.bytes(created_) + out_leaves * (8 + payload_);
  }

  Status try_balance(size_t i0, size_t i1, uint64_t from, uint64_t to, Window* w, bool* fits) {
    *fits = false;
    WEAVER_RETURN_IF_ERROR(collect_layer(i0, i1, from, to, fits));
    if (!*fits) return Status::Ok();
    local_.clear();
    local_.insert(local_.end(), layer_.begin(), layer_.begin() + layer_before_);
    local_.insert(local_.end(), keys_.begin() + i0, keys_.begin() + i1);
    local_.insert(local_.end(), layer_.begin() + layer_before_, layer_.end());
    const uint64_t before = held(i1 - i0) - ripple_.bytes(created_);
    if (!ripple_.run(local_, &created_, before < bytes_ ? bytes_ - before : 0)) {
      *fits = false;
      return Status::Ok();
    }
    if (held(i1 - i0) > bytes_) {
      *fits = false;
      return Status::Ok();
    }
    return refine(keys_.data() + i0, payloads_.data() + i0 * payload_, i1 - i0, created_, from, to,
                  w, fits);
  }

  // The leaves outside [from, to) that meet the block of an own leaf, in
  // key order, into layer_ (those before the window first).  An own leaf
  // whose block lies inside the coarsest octant of the window holding it
  // asks for nothing.
  Status collect_layer(size_t i0, size_t i1, uint64_t from, uint64_t to, bool* fits) {
    asked_.clear();
    recent_.clear();
    // The octants asked, with the sort's buffer, within a quarter of the
    // memory: compacted when they reach it, the window cut if that fails.
    const size_t ask_cap = std::max<uint64_t>(1024, bytes_ / 64);
    uint64_t anc = 0, anc_end = 0;  // the coarsest octant inside the window holding the leaf
    uint32_t leaving = 0;           // its neighbours not inside the window
    for (size_t i = i0; i < i1; ++i) {
      const uint64_t key = keys_[i];
      if (key < anc || key >= anc_end) {
        anc = key;
        while (octant_key_level(anc) > 0 && within(octant_key_parent(anc), from, to)) {
          anc = octant_key_parent(anc);
        }
        anc_end = octant_key_subtree_end(anc);
        leaving = neighbours_leaving(anc, from, to);
      }
      // Most leaves' neighbours all lie in neighbours of anc inside the
      // window: they ask for nothing, and their neighbours go untried.
      if (leaving == 0) continue;
      const unsigned sides = touched_sides(key, octant_key_level(anc));
      if ((kReachable[sides] & leaving) == 0) continue;
      const uint32_t crossing = kCrossing[sides];
      for (uint32_t bits = crossing; bits != 0; bits &= bits - 1) {
        uint64_t nb = 0;
        if (octant_key_neighbour(key, kAllDirections[std::countr_zero(bits)], &nb) &&
            !within(nb, from, to)) {
          // Leaves side by side ask for the same octants across an edge
          // or corner: a repeat found among the last asked is not kept.
          if (recent_.seen(nb)) continue;
          asked_.push_back(nb);
        }
      }
      if (asked_.size() >= ask_cap) {
        compact_asked();
        if (asked_.size() >= ask_cap / 2) return Status::Ok();  // too many: cut the window
      }
    }
    compact_asked();
    layer_.clear();
    uint64_t cap = bytes_ / 64;  // each layer leaf: in the layer, the local set and the map
    const uint64_t own = i1 - i0;
    const bool whole = own == keys_.size() && own >= layer_window_;
    if (layer_limit_ > 0 && whole) cap = std::min<uint64_t>(cap, layer_limit_ * double(own));
    // Past the cap: a whole window outweighed gives up, others are cut.
    auto over = [&] {
      outweighed_ = layer_limit_ > 0 && whole && layer_.size() > layer_limit_ * double(own);
      return Status::Ok();
    };
    ForwardFloor before, after;
    WEAVER_RETURN_IF_ERROR(before.open(leaves_));
    for (uint64_t k : asked_) {
      if (k >= from) break;
      WEAVER_RETURN_IF_ERROR(
          collect_range(before, k, std::min(octant_key_subtree_end(k), from), from, to));
      if (layer_.size() > cap) return over();
    }
    layer_before_ = layer_.size();
    WEAVER_RETURN_IF_ERROR(after.open(leaves_, to));
    for (uint64_t k : asked_) {
      const uint64_t end = octant_key_subtree_end(k);
      if (end <= to) continue;
      WEAVER_RETURN_IF_ERROR(collect_range(after, std::max(k, to), end, from, to));
      if (layer_.size() > cap) return over();
    }
    *fits = true;
    return Status::Ok();
  }

  // asked_ sorted, once each, keeping the outermost of nested octants (an
  // ancestor's key comes first).
  void compact_asked() {
    radix_sort_by(asked_, scratch_, [](uint64_t k) { return k; });
    size_t kept = 0;
    uint64_t covered = 0;
    for (uint64_t k : asked_) {
      if (kept > 0 && k < covered) continue;
      asked_[kept++] = k;
      covered = octant_key_subtree_end(k);
    }
    asked_.resize(kept);
  }

  // The leaves meeting [lo, hi) (the one holding lo, and those with keys in
  // it) outside [from, to), into layer_.  Calls come in key order.
  Status collect_range(ForwardFloor& f, uint64_t lo, uint64_t hi, uint64_t from, uint64_t to) {
    auto keep = [&](uint64_t key) {
      if ((key < from || key >= to) && (layer_.empty() || layer_.back() != key)) {
        layer_.push_back(key);
      }
    };
    WEAVER_RETURN_IF_ERROR(f.advance_to(lo));
    if (f.has_last() && lo < octant_key_subtree_end(f.last())) keep(f.last());
    while (f.has_next() && f.next_key() < hi) {
      WEAVER_RETURN_IF_ERROR(f.advance_to(f.next_key()));
      keep(f.last());
    }
    return Status::Ok();
  }

  // The n leaves at keys (their payloads at payloads) split just enough to
  // resolve `created`, appended to w's refinement; undone if the
  // refinement outgrows the memory.  from and to bound their keys.
  Status refine(const uint64_t* keys, const std::byte* payloads, size_t n,
                const std::vector<uint64_t>& created, uint64_t from, uint64_t to, Window* w,
                bool* fits) {
    *fits = false;
    const size_t at = w->keys.size();
    const uint64_t limit = bytes_ > held(0) ? (bytes_ - held(0)) / (8 + payload_) : 0;
    uint64_t split = 0;
    bool over = false;
    // A row goes where the count of keys says; the bytes grow in doubling
    // steps and are trimmed at the end (a resize for each row cost more
    // than the rest of the refinement).
    auto row = [&] { return w->payloads.data() + (w->keys.size() - 1) * payload_; };
    auto add = [&](uint64_t key, size_t i) {
      w->keys.push_back(key);
      const size_t end = w->keys.size() * payload_;
      if (end > w->payloads.size()) w->payloads.resize(std::max(end, 2 * w->payloads.size()));
      copy_bytes(row(), payloads + i * payload_, payload_);
      if (w->keys.size() - at > limit) over = true;
    };
    size_t last_split = SIZE_MAX;
    const Status st = resolve_leaves(
        keys, n, created,
        [&](size_t i) {
          add(keys[i], i);
          return Status::Ok();
        },
        [&](size_t i, uint64_t key, bool is_new) {
          if (i != last_split) last_split = i, ++split;
          add(key, i);
          if (is_new && fill_ && payload_ > 0) {
            fill_(octant_from_key(key), row());
          }
          return over ? Status::Internal("the window outgrew its memory") : Status::Ok();
        });
    if (over) {  // stopped: undone, to be cut in two
      w->keys.resize(at);
      w->payloads.resize(at * payload_);
      return Status::Ok();
    }
    w->payloads.resize(w->keys.size() * payload_);
    WEAVER_RETURN_IF_ERROR(st);
    for (size_t j = at; j < w->keys.size(); ++j) ++w->levels[octant_key_level(w->keys[j])];
    w->split += split;
    w->created += std::lower_bound(created.begin(), created.end(), to) -
                  std::lower_bound(created.begin(), created.end(), from);
    w->layer += layer_.size();
    *fits = true;
    return Status::Ok();
  }

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

}  // namespace

Status window_options(Database& db, BTree& leaves, const BalanceOptions& o,
                      const BalanceMemory& memory, std::vector<std::unique_ptr<BTree>>* more,
                      WindowOptions* wo) {
  wo->readers = {&leaves};
  for (int i = 1; i < o.threads; ++i) {
    more->emplace_back();
    WEAVER_RETURN_IF_ERROR(db.open_table(kOctantTable, memory.leaf_pool, &more->back()));
    wo->readers.push_back(more->back().get());
  }
  wo->memory = memory.windows;
  wo->window_leaves = o.window_leaves;
  // Auto gives windows up where their layers outweigh them; windows asked
  // for, where their layers are many times as long (cut after cut would
  // read them again and again).
  const bool auto_way = o.algorithm == BalanceOptions::Algorithm::kAuto;
  wo->layer_limit = auto_way ? 1.0 : 16.0;
  // Tests' short windows: auto gives them up when outweighed; all are cut
  // down to one leaf.
  if (o.window_leaves > 0) {
    if (auto_way) wo->layer_window = std::min(wo->layer_window, o.window_leaves);
    wo->least_cut = 1;
  }
  return Status::Ok();
}

bool one_window_may_fit(const BTree& leaves, uint64_t memory) {
  return leaves.size() * (kWholeBytesPerLeaf + leaves.payload_size()) <= memory;
}

namespace {

// Reads every leaf of the table into *t and ripples them all on `threads`
// threads; false in *fits if `memory` does not hold them.
Status ripple_whole(BTree& leaves, uint64_t memory, int threads, WholeTable* t, bool* fits) {
  *fits = false;
  const uint64_t n = leaves.size();
  if (!one_window_may_fit(leaves, memory)) return Status::Ok();
  WEAVER_RETURN_IF_ERROR(read_leaves(leaves, 0, n, true, &t->keys, &t->payloads));
  LocalRipple ripple(threads);
  *fits = ripple.run(t->keys, &t->created, memory - t->bytes());
  return Status::Ok();
}

}  // namespace

Status balance_in_windows(const WindowOptions& o, const FillPayload& fill, BTree& out,
                          BalanceResult* r, bool* fitted) {
  *fitted = true;
  BTree& first = *o.readers.at(0);
  const uint64_t total = first.size();
  const uint64_t lo = o.one_window ? 0 : std::min(o.first_leaf, total);
  const uint64_t hi = o.one_window ? total : std::min(o.end_leaf, total);
  const uint64_t n = hi - lo;
  if (n == 0) return Status::Ok();
  const int threads = static_cast<int>(o.readers.size());
  // Workers run ahead of the writer by a window each.
  const size_t in_flight = threads == 1 ? 1 : 2 * size_t(threads);
  uint64_t slot_bytes = o.memory / in_flight;
  uint64_t windows = 0;
  WholeTable whole;
  if (o.one_window) {
    bool fits = false;
    WEAVER_RETURN_IF_ERROR(ripple_whole(first, o.memory, threads, &whole, &fits));
    // What is left holds the blocks in flight.
    if (!fits || whole.bytes() + in_flight * kBlockLeaves * kBlockBytesPerLeaf > o.memory) {
      *fitted = false;
      return Status::Ok();
    }
    slot_bytes = (o.memory - whole.bytes()) / in_flight;
    windows = (n + kBlockLeaves - 1) / kBlockLeaves;
  } else {
    // A window's own leaves, read, and their refinement, about four times
    // as many, beside the local set, the ripple's work and what it creates.
    uint64_t leaves_per = std::max<uint64_t>(
        1024, slot_bytes / (4 * (8 + first.payload_size()) + kRippleBytesPerLeaf));
    if (o.window_leaves > 0) leaves_per = std::min(leaves_per, o.window_leaves);
    windows = std::max<uint64_t>(1, (n + leaves_per - 1) / leaves_per);
    if (threads > 1) windows = std::max<uint64_t>(windows, 4 * uint64_t(threads));
    windows = std::min(windows, std::max<uint64_t>(n, 1));
  }

  std::vector<std::unique_ptr<WindowWorker>> workers;
  for (int i = 0; i < threads; ++i) {
    workers.push_back(std::make_unique<WindowWorker>(*o.readers[i], slot_bytes, fill, o));
    if (o.one_window) workers.back()->share_whole(&whole);
  }
  // Where the windows part, found before the workers use the first handle.
  std::vector<uint64_t> starts(windows + 1, 0);
  for (uint64_t i = 0; i <= windows && !o.one_window; ++i) {
    const uint64_t at = lo + n * i / windows;
    if (at == 0 || at >= total) {
      starts[i] = at == 0 ? 0 : UINT64_MAX;
    } else {
      WEAVER_RETURN_IF_ERROR(first.select(at, &starts[i], nullptr));
    }
  }
  std::atomic<bool> given_up{false};
  for (auto& w : workers) w->share_giving_up(&given_up);
  WorkQueue<Window> queue;
  std::vector<std::thread> pool;
  if (threads > 1) {
    for (int i = 0; i < threads; ++i) {
      pool.emplace_back([&, i] {
        while (Window* w = queue.pop()) {
          workers[i]->run(w);
          queue.finish(w);
        }
      });
    }
  }
  uint64_t next = 0;
  // Refinements written, kept for their buffers: a window's refinement
  // of tens of MB, allocated afresh, is mapped and faulted in page by page
  // (at 1 Hz on one thread, 2 s of system time).
  std::vector<std::unique_ptr<Window>> spare;
  auto add = [&](std::deque<std::unique_ptr<Window>>* flight) {
    auto w = std::make_unique<Window>();
    if (!spare.empty()) {
      w->keys.swap(spare.back()->keys);
      w->payloads.swap(spare.back()->payloads);
      w->keys.clear();
      w->payloads.clear();
      spare.pop_back();
    }
    w->first = n * next / windows;
    w->count = n * (next + 1) / windows - w->first;
    if (o.one_window) {  // a block: its leaves are read already
      const uint64_t end = w->first + w->count;
      w->from = whole.keys[w->first];
      w->to = end < n ? whole.keys[end] : UINT64_MAX;
    } else {
      w->from = starts[next];
      w->to = starts[next + 1];
    }
    ++next;
    if (threads > 1) queue.push(w.get());
    flight->push_back(std::move(w));
  };
  std::deque<std::unique_ptr<Window>> flight;  // key order
  Status st;
  uint64_t read = 0;
  while (st.ok()) {
    while (flight.size() < in_flight && next < windows) add(&flight);
    if (flight.empty()) break;
    Window* head = flight.front().get();
    if (threads > 1) {
      queue.wait_done(head);
    } else {
      workers[0]->run(head);
    }
    st = head->status;
    if (st.ok() && !head->fitted) {
      *fitted = false;
      break;
    }
    if (st.ok()) st = out.append_batch(head->keys.data(), head->payloads.data(), head->keys.size());
    if (!st.ok()) break;
    for (int l = 0; l <= kMaxLevel; ++l) r->levels[l] += head->levels[l];
    r->output_leaves += head->keys.size();
    r->split += head->split;
    r->required += head->created;
    r->layer_leaves += head->layer;
    ++r->windows;
    read += head->count;
    if (o.progress) o.progress(read, double(read) / std::max<uint64_t>(n, 1));
    spare.push_back(std::move(flight.front()));
    flight.pop_front();
  }
  r->input_leaves = read;
  r->by_windows = *fitted;
  if (o.one_window) r->windows = 1;  // its blocks are not windows of their own
  if (threads > 1) {
    for (auto& w : flight) queue.wait_done(w.get());
    queue.stop();
    for (auto& t : pool) t.join();
  }
  return st;
}

}  // namespace weaver
