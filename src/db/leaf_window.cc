#include "db/leaf_window.h"

#include <algorithm>

namespace weaver {

Status LeafWindow::page_for(uint64_t key, Page** page, uint64_t* leaf_rank) {
  *page = nullptr;
  const auto covers = [key](const Page& p) {
    return !p.keys.empty() && p.keys.front() <= key && key <= p.covers_to;
  };
  if (covers(pages_[last_])) {
    *page = &pages_[last_];
    (*page)->used = ++clock_;
    return Status::Ok();
  }
  size_t oldest = 0;
  for (size_t i = 0; i < kPages; ++i) {
    if (covers(pages_[i])) {
      last_ = i;
      *page = &pages_[i];
      (*page)->used = ++clock_;
      return Status::Ok();
    }
    if (pages_[i].used < pages_[oldest].used) oldest = i;
  }
  Page& p = pages_[oldest];
  ++decodes_;
  WEAVER_RETURN_IF_ERROR(
      table_.leaf_keys(key, &p.keys, &p.first_rank, payloads_ ? &p.payloads : nullptr));
  p.used = ++clock_;
  if (p.keys.empty() || key < p.keys.front()) {
    *leaf_rank = p.first_rank;
    p.keys.clear();  // not a page that covers anything: leave it to the tree
    return Status::Ok();
  }
  // The descent chose this leaf for key, so the next leaf's separator, and
  // every key of that leaf, is past key: nothing lies between.
  p.covers_to = std::max(p.keys.back(), key);
  last_ = oldest;
  *page = &p;
  return Status::Ok();
}

Status LeafWindow::sparse_floor(uint64_t key, Floor* out) {
  single_.resize(table_.payload_size() + 1);
  WEAVER_RETURN_IF_ERROR(table_.floor_rank(key, &out->key, payloads_ ? single_.data() : nullptr,
                                           &out->rank, &out->found, recycle_));
  out->payload = out->found && payloads_ ? single_.data() : nullptr;
  return Status::Ok();
}

Status LeafWindow::floor(uint64_t key, Floor* out) {
  *out = Floor{};
  if (sparse_) return sparse_floor(key, out);
  Page* p = nullptr;
  uint64_t leaf_rank = 0;
  WEAVER_RETURN_IF_ERROR(page_for(key, &p, &leaf_rank));
  if (p != nullptr) {  // keys.front() <= key: the floor is here
    const size_t at =
        size_t(std::upper_bound(p->keys.begin(), p->keys.end(), key) - 1 - p->keys.begin());
    out->found = true;
    out->key = p->keys[at];
    out->rank = p->first_rank + at;
    if (payloads_) out->payload = p->payloads.data() + at * table_.payload_size();
    return Status::Ok();
  }
  // key is below its leaf's first key: its floor, if any, ends the leaf before.
  if (leaf_rank == 0) return Status::Ok();
  single_.resize(table_.payload_size() + 1);
  out->found = true;
  out->rank = leaf_rank - 1;
  out->payload = payloads_ ? single_.data() : nullptr;
  return table_.select(out->rank, &out->key, payloads_ ? single_.data() : nullptr);
}

Status LeafWindow::get(uint64_t key, const std::byte** payload, bool* found) {
  *found = false;
  if (sparse_) {
    Floor f;
    WEAVER_RETURN_IF_ERROR(sparse_floor(key, &f));
    *found = f.found && f.key == key;
    if (*found && payload != nullptr) *payload = f.payload;
    return Status::Ok();
  }
  Page* p = nullptr;
  uint64_t leaf_rank = 0;
  WEAVER_RETURN_IF_ERROR(page_for(key, &p, &leaf_rank));
  if (p == nullptr) return Status::Ok();  // before its leaf's first key: not there
  const auto at = std::lower_bound(p->keys.begin(), p->keys.end(), key);
  if (at == p->keys.end() || *at != key) return Status::Ok();
  *found = true;
  if (payloads_ && payload != nullptr) {
    *payload = p->payloads.data() + (at - p->keys.begin()) * table_.payload_size();
  }
  return Status::Ok();
}

}  // namespace weaver
