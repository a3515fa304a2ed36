#include "verify/leaf_window.h"

#include <algorithm>

namespace weaver {

Status RecentPages::page_for(uint64_t key, Page** page) {
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
  uint64_t first_rank = 0;
  WEAVER_RETURN_IF_ERROR(
      table_.leaf_keys(key, &p.keys, &first_rank, payloads_ ? &p.payloads : nullptr));
  p.used = ++clock_;
  if (p.keys.empty() || key < p.keys.front()) {
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

Status RecentPages::floor(uint64_t key, uint64_t* out, bool* found) {
  Page* p = nullptr;
  WEAVER_RETURN_IF_ERROR(page_for(key, &p));
  if (p == nullptr) return table_.floor(key, out, nullptr, found);
  // keys.front() <= key, so the floor is here.
  *out = *(std::upper_bound(p->keys.begin(), p->keys.end(), key) - 1);
  *found = true;
  return Status::Ok();
}

Status RecentPages::get(uint64_t key, const std::byte** payload, bool* found) {
  *found = false;
  Page* p = nullptr;
  WEAVER_RETURN_IF_ERROR(page_for(key, &p));
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
