// The mesh invariants of verify.h, given the octant and node tables.
#pragma once

#include "schema/status.h"
#include "storage/btree.h"
#include "util/progress.h"
#include "verify/problems.h"

namespace weaver {

// Classifies every node again from the leaves around it and compares.
// Returns an error only when a table cannot be read.
Status check_mesh_nodes(BTree& octants, BTree& nodes, const ProgressFn& progress,
                        Problems& problems, VerifyReport* report);

}  // namespace weaver
