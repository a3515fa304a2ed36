#include "storage/lsm_memtable.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <utility>

namespace weaver {

Memtable::Memtable(uint32_t payload_size, uint64_t budget_bytes)
    : payload_(payload_size),
      reserve_entries_(static_cast<size_t>(budget_bytes / (8 + 1 + payload_size + 4 + 8 + 16))) {}

size_t Memtable::probe(uint64_t key) const {
  const size_t mask = slots_.size() - 1;
  size_t s = (key * 0x9E3779B97F4A7C15ULL) >> (64 - std::countr_zero(slots_.size()));
  while (slots_[s] != 0 && keys_[slots_[s] - 1] != key) s = (s + 1) & mask;
  return s;
}

void Memtable::grow_hash() {
  if (keys_.capacity() == 0) {
    keys_.reserve(reserve_entries_);
    dead_.reserve(reserve_entries_);
    payloads_.reserve(reserve_entries_ * payload_);
    order_.reserve(reserve_entries_);
    sort_pairs_.reserve(reserve_entries_);
  }
  slots_.assign(std::max<size_t>(1024, 2 * slots_.size()), 0);
  for (size_t i = 0; i < keys_.size(); ++i) slots_[probe(keys_[i])] = static_cast<uint32_t>(i + 1);
}

void Memtable::upsert(uint64_t key, const std::byte* payload, bool tombstone) {
  if (2 * (keys_.size() + 1) > slots_.size()) grow_hash();
  const size_t s = probe(key);
  size_t i;
  if (slots_[s] != 0) {
    i = slots_[s] - 1;
    tombstones_ -= dead_[i];
  } else {
    if (!keys_.empty() && key < keys_.back()) in_order_ = false;
    i = keys_.size();
    keys_.push_back(key);
    dead_.push_back(0);
    payloads_.resize(payloads_.size() + payload_);
    slots_[s] = static_cast<uint32_t>(i + 1);
  }
  dead_[i] = tombstone ? 1 : 0;
  tombstones_ += dead_[i];
  std::byte* dst = payloads_.data() + size_t{payload_} * i;
  if (payload != nullptr && !tombstone) {
    std::memcpy(dst, payload, payload_);
  } else {
    std::memset(dst, 0, payload_);
  }
}

bool Memtable::find(uint64_t key, const std::byte** payload, bool* tombstone) const {
  if (keys_.empty()) return false;
  const size_t s = probe(key);
  if (slots_[s] == 0) return false;
  const size_t i = slots_[s] - 1;
  *payload = payloads_.data() + size_t{payload_} * i;
  *tombstone = dead_[i] != 0;
  return true;
}

void Memtable::sort() {
  if (sorted_ == keys_.size()) return;
  // The new entries, sorted by (key, index) pairs (no indirection while
  // comparing), then merged with the sorted ones.
  std::vector<std::pair<uint64_t, uint32_t>>& fresh = sort_pairs_;  // kept: no heap churn
  fresh.clear();
  for (size_t i = sorted_; i < keys_.size(); ++i) fresh.emplace_back(keys_[i], uint32_t(i));
  if (!in_order_) std::sort(fresh.begin(), fresh.end());
  const size_t old = order_.size();
  order_.resize(keys_.size());
  for (size_t j = 0; j < fresh.size(); ++j) order_[old + j] = fresh[j].second;
  if (old > 0 && keys_[order_[old - 1]] > fresh.front().first) {
    std::inplace_merge(order_.begin(), order_.begin() + old, order_.end(),
                       [this](uint32_t a, uint32_t b) { return keys_[a] < keys_[b]; });
  }
  sorted_ = keys_.size();
}

size_t Memtable::lower_bound(uint64_t key) const {
  return std::partition_point(order_.begin(), order_.end(),
                              [&](uint32_t i) { return keys_[i] < key; }) -
         order_.begin();
}

uint64_t Memtable::memory_bytes() const {
  // keys, flags, payloads, order, the sort pairs, and the hash.
  return keys_.size() * (8 + 1 + payload_ + 4 + 16) + slots_.size() * 4;
}

void Memtable::clear() {
  keys_.clear();
  dead_.clear();
  payloads_.clear();
  std::fill(slots_.begin(), slots_.end(), 0);
  order_.clear();
  sorted_ = 0;
  tombstones_ = 0;
  in_order_ = true;
}

}  // namespace weaver
