// The two-level bucket sort (see extract.h): on this thread, or with worker
// threads (extract_parallel.h).
#pragma once

#include <string>

#include "extract/extract.h"
#include "schema/status.h"

namespace weaver {

class BTree;
class Database;

// Appends the nodes of the octree in `octants` to `nodes` (empty), in buckets
// of level result->bucket_level (if >= 0) or of about result->bucket_leaves
// leaves; spill files go under scratch_path.
Status extract_by_sort(Database& db, BTree& octants, BTree& nodes, const std::string& scratch_path,
                       const ExtractMemory& memory, const ExtractOptions& options,
                       ExtractResult* result);

}  // namespace weaver
