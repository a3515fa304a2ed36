// The mesh invariants of verify.h, given the octant and node tables.
#pragma once

#include <functional>

#include "schema/status.h"
#include "storage/btree.h"
#include "util/progress.h"
#include "verify/problems.h"

namespace weaver {

// Classifies the nodes of ids [first, end) again from the leaves around
// them and compares; adds to report's nodes, dangling and corners counts,
// and calls checked(n) every so many nodes.  The tables are this call's
// alone (one range a thread, each with its own handles).  Returns an error
// only when a table cannot be read.
Status check_node_range(BTree& octants, BTree& nodes, uint64_t first, uint64_t end,
                        const std::function<void(uint64_t)>& checked, Problems& problems,
                        VerifyReport* report);

// After every node: each element's 8 corners were found at nodes (the
// report's counts, summed over the ranges), or the first element that
// lacks one is named.
Status check_corner_total(BTree& octants, BTree& nodes, Problems& problems, VerifyReport* report);

}  // namespace weaver
