// The search-based extraction (paper, section 3); see extract_search.cc.
#pragma once

#include <string>

#include "extract/extract.h"
#include "storage/btree.h"

namespace weaver {

// Appends the nodes of the octree in `octants` to `nodes` (empty), using a
// scratch node store within store_bytes: a B+tree file scratch_path.bt, or
// with lsm an LSM store in the directory scratch_path.lsm.  The classifier's
// cache of leaves holds 2^cache_bits keys.
Status extract_by_search(BTree& octants, BTree& nodes, const std::string& scratch_path,
                         uint64_t store_bytes, int cache_bits, bool lsm, ExtractResult* result);

}  // namespace weaver
