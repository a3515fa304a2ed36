#include "balance/window_worker.h"

#include <algorithm>
#include <bit>
#include <cstring>

#include "balance/window_edges.h"
#include "schema/octant.h"
#include "util/radix_sort.h"
#include "util/resolve_split.h"

namespace weaver {

using window_edges::kCrossing;
using window_edges::kReachable;
using window_edges::neighbours_leaving;
using window_edges::touched_sides;
using window_edges::within;

namespace {

// A payload row copied (none where the table has no payload).
void copy_bytes(std::byte* to, const std::byte* from, size_t n) {
  if (n > 0) std::memcpy(to, from, n);
}

}  // namespace

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

void WindowWorker::run(Window* w) {
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
  w->status = bounds(w);
  if (w->status.ok()) w->status = read(*w);
  if (w->status.ok()) w->status = balance(0, keys_.size(), w->from, w->to, w);
  if (outweighed_) give_up(w);
}

void WindowWorker::give_up(Window* w) {
  w->fitted = false;
  if (given_up_ != nullptr) given_up_->store(true);
}

Status WindowWorker::bounds(Window* w) {
  auto key_at = [&](uint64_t i, uint64_t* key) {
    if (i == 0 || i >= leaves_.size()) {
      *key = i == 0 ? 0 : UINT64_MAX;
      return Status::Ok();
    }
    return leaves_.select(i, key, nullptr);
  };
  WEAVER_RETURN_IF_ERROR(key_at(w->first, &w->from));
  return key_at(w->first + w->count, &w->to);
}

Status WindowWorker::read(const Window& w) {
  return read_leaves(leaves_, w.from, w.count, false, &keys_, &payloads_);
}

Status WindowWorker::balance(size_t i0, size_t i1, uint64_t from, uint64_t to, Window* w) {
  bool fits = false;
  WEAVER_RETURN_IF_ERROR(try_balance(i0, i1, from, to, w, &fits));
  if (fits || outweighed_) return Status::Ok();
  if (i1 - i0 <= least_cut_) {  // short, and still too much: give up
    w->fitted = false;
    return Status::Ok();
  }
  w->cut = true;
  const size_t mid = i0 + (i1 - i0) / 2;
  WEAVER_RETURN_IF_ERROR(balance(i0, mid, from, keys_[mid], w));
  return w->fitted ? balance(mid, i1, keys_[mid], to, w) : Status::Ok();
}

uint64_t WindowWorker::held(uint64_t out_leaves, bool allocated) const {
  auto words = [&](const auto& v) -> uint64_t { return allocated ? v.capacity() : v.size(); };
  const uint64_t own =
      words(keys_) + words(asked_) + words(scratch_) + words(layer_) + words(local_);
  return 8 * own + words(payloads_) + ripple_.bytes(created_) + out_leaves * (8 + payload_);
}

Status WindowWorker::try_balance(size_t i0, size_t i1, uint64_t from, uint64_t to, Window* w,
                                 bool* fits) {
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
  return refine(keys_.data() + i0, payloads_.data() + i0 * payload_, i1 - i0, created_, from, to, w,
                fits);
}

Status WindowWorker::collect_layer(size_t i0, size_t i1, uint64_t from, uint64_t to, bool* fits) {
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

void WindowWorker::compact_asked() {
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

Status WindowWorker::collect_range(ForwardFloor& f, uint64_t lo, uint64_t hi, uint64_t from,
                                   uint64_t to) {
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

Status WindowWorker::refine(const uint64_t* keys, const std::byte* payloads, size_t n,
                            const std::vector<uint64_t>& created, uint64_t from, uint64_t to,
                            Window* w, bool* fits) {
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
      [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) add(keys[i], i);
        return Status::Ok();
      },
      [&](size_t i, uint64_t key, bool is_new) {
        if (i != last_split) last_split = i, ++split;
        add(key, i);
        if (is_new && fill_ && payload_ > 0 && !fill_(octant_from_key(key), row())) {
          w->keys.pop_back();  // air over the ground: no leaf
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
  w->peak = std::max<uint64_t>(w->peak, held(w->keys.size(), false));
  *fits = true;
  return Status::Ok();
}

}  // namespace weaver
