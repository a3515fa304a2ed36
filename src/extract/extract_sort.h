// The two-level bucket sort (see extract.h): on this thread, or with worker
// threads (extract_parallel.h).
#pragma once

#include <string>
#include <vector>

#include "extract/extract.h"
#include "extract/spill_store.h"
#include "schema/status.h"

namespace weaver {

class BTree;
class Database;

// Hands the nodes of the octree in `octants` to `nodes` in key order, in buckets
// of level result->bucket_level (if >= 0) or of about result->bucket_leaves
// leaves; spill files go under scratch_path.
// A part (BucketPolicy: start, stop, first_leaf, ghosts, whose corners in
// the part wait in the spill store from the start) restricts it to one
// rank's nodes.
struct ExtractPart {
  uint64_t start = 0, stop = UINT64_MAX, first_leaf = 0;
  std::vector<uint64_t> ghosts;  // sorted leaf keys of earlier parts
};
Status extract_by_sort(const Database& db, BTree& octants, const NodeBatchSink& nodes,
                       const std::string& scratch_path, const ExtractMemory& memory,
                       const ExtractOptions& options, ExtractResult* result,
                       ExtractPart* part = nullptr);

}  // namespace weaver
