// `weaver compact`: every sharded table of a database (db/database.h) joined
// into one B+tree file by sorted append, committed in one manifest.  The
// file is the one the single-process writer of the same records writes:
// same options, the shards' metadata merged (merge_shard_metadata), pages
// filled by the same sorted append.  Tables of one file are left as they
// are; a failure leaves the database as it was.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "schema/status.h"
#include "util/memory_budget.h"

namespace weaver {

struct CompactResult {
  // One per table joined: its name, the shards it had and its records.
  struct Table {
    std::string name;
    uint64_t shards = 0, records = 0, bytes = 0;
  };
  std::vector<Table> tables;
};

// memory bounds the shards' reader pools and the new table's writer pool.
Status compact_database(const std::string& db_dir, MemoryBudget memory, CompactResult* result);

}  // namespace weaver
