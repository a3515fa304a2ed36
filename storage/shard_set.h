// A table cut into shards, read as one: B+tree files holding disjoint,
// increasing key ranges (as MPI ranks will write them, one each: issue 28),
// answering as a single tree of all their records would.  Ranks are global:
// a record's rank is the count of the shards before its own plus its rank in
// its shard, so ids stay what they are whatever the cut.
//
// The read half of a sharded table, to which BTree will hand its reads when
// its table is sharded (the stages hold BTree&).  Read-only; not thread-safe
// (a B+tree serves one thread).
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
  uint64_t size() const { return before_.back(); }
  uint32_t payload_size() const { return shards_.front()->payload_size(); }

  // As BTree's.
  Status get(uint64_t key, std::byte* payload_out, bool* found);
  Status floor(uint64_t key, uint64_t* key_out, std::byte* payload_out, bool* found);
  // The number of keys < key, and whether key is there.
  Status rank_exact(uint64_t key, uint64_t* rank, bool* present);
  // The record of global rank `index`; InvalidArgument past the last.
  Status select(uint64_t index, uint64_t* key_out, std::byte* payload_out);
  // A cursor at the first key >= key, going on from one shard to the next.
  Status seek(uint64_t key, std::unique_ptr<Cursor>* out);

 private:
  class ShardCursor;
  ShardSet() = default;
  // The last shard whose first key is <= key; -1 when key is below them all.
  int shard_of(uint64_t key) const;

  std::vector<std::unique_ptr<BTree>> shards_;
  std::vector<uint64_t> first_, last_;  // each shard's first and last key
  std::vector<uint64_t> before_;        // records in the shards before shard i; size + 1 entries
};

}  // namespace weaver
