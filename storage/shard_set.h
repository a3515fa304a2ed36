// A table cut into shards, read as one: B+tree files holding disjoint,
// increasing key ranges (as MPI ranks write them, one each: issue 28),
// answering as a single tree of all their records would.  Ranks are global:
// a record's rank is the count of the shards before its own plus its rank in
// its shard, so ids stay what they are whatever the cut.
//
// The read half of a sharded BTree (BTree::open_sharded), to which the tree
// hands every read, so that the stages, which hold BTree&, read a sharded
// table unchanged.  Read-only; not thread-safe (a B+tree serves one thread).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "storage/btree.h"
#include "storage/store.h"

namespace weaver {

class ShardSet {
 public:
  // REQUIRES of the shards, else Corruption naming the shard: in key order,
  // each non-empty, each one's keys above the one before's; one payload size.
  static Status make(std::vector<std::unique_ptr<BTree>> shards, std::unique_ptr<ShardSet>* out);

  size_t shard_count() const { return shards_.size(); }
  BTree& shard(size_t i) { return *shards_[i]; }
  uint64_t size() const { return before_.back(); }
  uint32_t payload_size() const { return shards_.front()->payload_size(); }
  // Each shard's first and last key.
  uint64_t first_key(size_t i) const { return first_[i]; }
  uint64_t last_key(size_t i) const { return last_[i]; }

  // As BTree's.
  Status get(uint64_t key, std::byte* payload_out, bool* found);
  Status floor(uint64_t key, uint64_t* key_out, std::byte* payload_out, bool* found);
  // The number of keys < key, and whether key is there.
  Status rank_exact(uint64_t key, uint64_t* rank, bool* present);
  // The record of global rank `index`; InvalidArgument past the last.
  Status select(uint64_t index, uint64_t* key_out, std::byte* payload_out);
  // The leaf of the shard where key is or would be, first_rank global.
  Status leaf_keys(uint64_t key, std::vector<uint64_t>* keys, uint64_t* first_rank,
                   std::vector<std::byte>* payloads);
  // A cursor at the first key >= key, going on from one shard to the next
  // (each shard's tree knows the next: BTreeCursor::next_leaf).
  Status position(uint64_t key, bool keys_only, BTreeCursor* cursor);
  // Every shard's invariants, and the order between shards.
  Status check_invariants();

 private:
  ShardSet() = default;
  // The last shard whose first key is <= key; -1 when key is below them all.
  int shard_of(uint64_t key) const;

  std::vector<std::unique_ptr<BTree>> shards_;
  std::vector<uint64_t> first_, last_;  // each shard's first and last key
  std::vector<uint64_t> before_;        // records in the shards before shard i; size + 1 entries
};

}  // namespace weaver
