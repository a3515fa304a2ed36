#include "balance/window_balance.h"

#include <algorithm>
#include <atomic>
#include <memory>

#include "balance/window_plan.h"
#include "balance/window_worker.h"
#include "util/local_ripple.h"
#include "util/ordered_run.h"

namespace weaver {
namespace {

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

// A written window's counts, into the result.
void count_window(const Window& w, BalanceResult* r) {
  for (int l = 0; l <= kMaxLevel; ++l) r->levels[l] += w.levels[l];
  r->output_leaves += w.keys.size();
  r->split += w.split;
  r->required += w.created;
  r->layer_leaves += w.layer;
  ++r->windows;
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
  // Workers run ahead of the oldest window by a window each.
  const size_t in_flight = threads == 1 ? 1 : 2 * size_t(threads);
  uint64_t slot_bytes = o.memory / in_flight;
  WholeTable whole;
  // Windows: a window's own leaves, read, and their refinement, about four
  // times as many, beside the local set, the ripple's work and what it
  // creates, until windows are measured.  Several threads share at least
  // four windows each.
  uint64_t first_per_leaf = 4 * (8 + first.payload_size()) + kRippleBytesPerLeaf;
  uint64_t longest = threads > 1 ? (n + 4 * threads - 1) / (4 * threads) : n;
  if (o.one_window) {
    bool fits = false;
    WEAVER_RETURN_IF_ERROR(ripple_whole(first, o.memory, threads, &whole, &fits));
    // What is left holds the blocks in flight.
    if (!fits || whole.bytes() + in_flight * kBlockLeaves * kBlockBytesPerLeaf > o.memory) {
      *fitted = false;
      return Status::Ok();
    }
    slot_bytes = (o.memory - whole.bytes()) / in_flight;
    first_per_leaf = 1;
    longest = kBlockLeaves;
  } else if (o.window_leaves > 0) {
    longest = std::min(longest, o.window_leaves);
  }
  WindowPlan plan(lo, n, slot_bytes, first_per_leaf, longest);

  std::vector<std::unique_ptr<WindowWorker>> workers;
  for (int i = 0; i < threads; ++i) {
    workers.push_back(std::make_unique<WindowWorker>(*o.readers[i], slot_bytes, fill, o));
    if (o.one_window) workers.back()->share_whole(&whole);
  }
  std::atomic<bool> given_up{false};
  for (auto& w : workers) w->share_giving_up(&given_up);
  auto make = [&](Window* w) {
    if (!plan.more()) return false;
    w->reset();
    plan.next(&w->first, &w->count);
    if (o.one_window) {  // a block: its leaves are read already
      const uint64_t end = w->first + w->count;
      w->from = whole.keys[w->first];
      w->to = end < n ? whole.keys[end] : UINT64_MAX;
    }  // a window's worker finds its keys' bounds
    return true;
  };
  Status st;
  uint64_t read = 0;
  auto write = [&](Window* w) {
    st = w->status;
    if (st.ok() && !w->fitted) {
      *fitted = false;
      return false;
    }
    if (st.ok()) st = out.append_batch(w->keys.data(), w->payloads.data(), w->keys.size());
    if (!st.ok()) return false;
    count_window(*w, r);
    if (!o.one_window) plan.learn(w->count, w->peak, w->cut);
    read += w->count;
    if (o.progress) o.progress(read, double(read) / std::max<uint64_t>(n, 1));
    return true;
  };
  OrderedRun<Window> run(
      in_flight, make, [&](int i, Window* w) { workers[i]->run(w); }, write);
  run.go(threads);
  r->input_leaves = read;
  r->by_windows = *fitted;
  if (o.one_window) r->windows = 1;  // its blocks are not windows of their own
  return st;
}

}  // namespace weaver
