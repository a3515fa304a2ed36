// The search-based extraction (paper, section 3); see extract_search.cc.
#pragma once

#include <string>

#include "extract/extract.h"
#include "storage/btree.h"

namespace weaver {

// Appends the nodes of the octree in `octants` to `nodes` (empty), using a
// scratch node B-tree at scratch_path with a pool of pool_bytes.
Status extract_by_search(BTree& octants, BTree& nodes, const std::string& scratch_path,
                         uint64_t pool_bytes, ExtractResult* result);

}  // namespace weaver
