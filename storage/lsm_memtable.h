// The LSM's memtable: the newest writes, in memory.  Entries (a key, a
// tombstone flag, a payload) go in arrival order into flat arrays, with an
// open-addressing hash from key to entry for point lookups and overwrites.
// Key order is made only when something reads in order (a scan, a floor, a
// flush): the entries added since the last sort are sorted and merged into
// the sorted order then.  So a write costs a hash probe and a copy, and a
// build-then-read workload sorts once.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace weaver {

class Memtable {
 public:
  // budget_bytes: what memory_bytes() may reach before the owner flushes;
  // the arrays are reserved for that many entries up front, so they never
  // grow by doubling past it.
  Memtable(uint32_t payload_size, uint64_t budget_bytes);

  // Inserts or overwrites; payload may be null (zeros).
  void put(uint64_t key, const std::byte* payload) { upsert(key, payload, false); }
  // Records a tombstone for key.
  void erase(uint64_t key) { upsert(key, nullptr, true); }

  // The entry for key, if the memtable has one.
  bool find(uint64_t key, const std::byte** payload, bool* tombstone) const;

  // Sorted access.  REQUIRES: sort() since the last write.
  void sort();
  size_t lower_bound(uint64_t key) const;  // the first sorted position with a key >= key
  uint64_t key_at(size_t pos) const { return keys_[order_[pos]]; }
  bool tombstone_at(size_t pos) const { return dead_[order_[pos]] != 0; }
  const std::byte* payload_at(size_t pos) const {
    return payloads_.data() + size_t{payload_} * order_[pos];
  }

  size_t size() const { return keys_.size(); }
  bool empty() const { return keys_.empty(); }
  size_t tombstones() const { return tombstones_; }
  // Bytes held, counting the hash and the room sorting needs.
  uint64_t memory_bytes() const;
  void clear();

 private:
  void upsert(uint64_t key, const std::byte* payload, bool tombstone);
  size_t probe(uint64_t key) const;
  void grow_hash();

  uint32_t payload_;
  size_t reserve_entries_;
  std::vector<uint64_t> keys_;
  std::vector<uint8_t> dead_;
  std::vector<std::byte> payloads_;
  std::vector<uint32_t> slots_;  // entry index + 1; 0 is empty
  std::vector<uint32_t> order_;  // entry indexes, sorted by key up to sorted_
  std::vector<std::pair<uint64_t, uint32_t>> sort_pairs_;
  size_t sorted_ = 0;  // entries covered by order_
  size_t tombstones_ = 0;
  bool in_order_ = true;
};

}  // namespace weaver
