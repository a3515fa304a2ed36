// One rank's part of a parallel 2:1 balance (weaver-mpi balance), in a fixed
// number of message rounds: two, whatever the levels.
//
// The leaves are cut into `ranks` runs of equal count (rank r owns the r-th,
// a contiguous range of the Z-order).  The balanced refinement of a leaf o
// depends only on the leaves of the input that meet o's insulation layer,
// the 3 x 3 x 3 block of o-sized octants around o (Isaac, Burstedde and
// Ghattas, "Low-cost parallel algorithms for 2:1 octree balance", IPDPS
// 2012; p4est_balance_ext in p4est's p4est_algorithms.c uses the same
// layer): a finer leaf further away refines its surroundings by less than o
// before the ripple reaches o.  So each rank
//   1. names, for each rank s, the octants of its leaves' insulation layers
//      that reach into s's part of the Z-order (round 1: the queries),
//   2. answers the queries it gets with its leaves that meet the queried
//      octants (round 2: the insulation layer itself),
//   3. balances its own leaves together with the ones that arrived, in a
//      scratch database, by the serial out-of-core balance (balance.h), and
//      keeps the leaves inside its own: its shard of the balanced table.
// The shards, in rank order, are the table the serial balance writes.
#pragma once

#include <string>
#include <vector>

#include "balance/balance.h"
#include "db/database.h"
#include "util/rank_exchange.h"

namespace weaver {

struct BalanceShardResult {
  BalanceResult balance;                        // of the rank's own leaves
  uint64_t queries_sent = 0;                    // insulation octants asked of other ranks
  uint64_t layer_received = 0;                  // their leaves that arrived
  uint64_t bytes_sent = 0, bytes_received = 0;  // both rounds
  uint64_t table_bytes = 0;                     // the shard written
};

// Writes rank `rank`'s shard of the balanced octant table of db_dir into the
// new file `file` (synced; *entry describes it, records 0 and no file for a
// rank without leaves).  Its scratch database lies in db_dir and is removed.
// The caller commits the shards (Database::commit_shards).
Status balance_shard(const std::string& db_dir, const BalanceOptions& options, int rank, int ranks,
                     const std::string& file, const RankExchange& exchange,
                     BalanceShardResult* result, ShardEntry* entry);

}  // namespace weaver
