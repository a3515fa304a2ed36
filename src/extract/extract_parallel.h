// The bucket sort with worker threads: this thread reads buckets in Z-order
// (and routes spills), workers extract them, this thread writes them back in
// Z-order.  At most 2 x threads buckets are in flight.
#pragma once

#include "db/database.h"
#include "extract/bucket_worker.h"
#include "extract/extract.h"

namespace weaver {

Status run_parallel(const Database& db, BTree& octants, const NodeBatchSink& nodes,
                    const BucketPolicy& policy, SpillStore& spills, const ExtractMemory& memory,
                    const ExtractOptions& options, ExtractResult* result);

// Appends a finished bucket's nodes, adds up its counts and reports
// progress (elements done of `elements`).
Status write_bucket(const BucketTask& t, const NodeBatchSink& nodes, uint64_t elements,
                    const ExtractOptions& options, ExtractResult* result);

}  // namespace weaver
