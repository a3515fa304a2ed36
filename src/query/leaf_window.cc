#include "query/leaf_window.h"

#include <algorithm>

namespace weaver {

Status LeafWindow::load(uint64_t key) {
  return t_.leaf_keys(key, &keys_, &first_rank_, payloads_ ? &vals_ : nullptr);
}

Status LeafWindow::sparse_floor(uint64_t key, Floor* out) {
  before_.resize(t_.payload_size() + 1);
  WEAVER_RETURN_IF_ERROR(
      t_.floor(key, &out->key, payloads_ ? before_.data() : nullptr, &out->found));
  if (!out->found) return Status::Ok();
  out->payload = payloads_ ? before_.data() : nullptr;
  return t_.rank(out->key, &out->rank);
}

Status LeafWindow::floor(uint64_t key, Floor* out) {
  *out = Floor{};
  if (sparse_) return sparse_floor(key, out);
  // The cached leaf answers keys within its first and last key; a key past
  // its last may still have its floor there, which a fresh descent tells.
  if (keys_.empty() || key < keys_.front() || key > keys_.back()) {
    WEAVER_RETURN_IF_ERROR(load(key));
    if (keys_.empty()) return Status::Ok();  // an empty table
  }
  const size_t at = size_t(std::upper_bound(keys_.begin(), keys_.end(), key) - keys_.begin());
  if (at > 0) {
    out->found = true;
    out->key = keys_[at - 1];
    out->rank = first_rank_ + at - 1;
    if (payloads_) out->payload = vals_.data() + (at - 1) * t_.payload_size();
    return Status::Ok();
  }
  // key is below the leaf's first key: its floor, if any, ends the leaf before.
  if (first_rank_ == 0) return Status::Ok();
  before_.resize(t_.payload_size());
  out->found = true;
  out->rank = first_rank_ - 1;
  out->payload = payloads_ ? before_.data() : nullptr;
  return t_.select(out->rank, &out->key, payloads_ ? before_.data() : nullptr);
}

}  // namespace weaver
