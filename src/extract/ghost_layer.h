// The ghost layer of a parallel extract (extract_shard): the leaves of
// earlier ranks that touch the nodes a rank owns.
//
// Rank r owns the node keys [start[r], start[r + 1]) (extract.h).  Every leaf
// that has a node on its closure has a Morton code no larger than the node's,
// so the leaves around r's nodes are r's own and some of earlier ranks': those
// whose far faces reach into r's range.  A leaf's closure outside its own
// subtree lies in the boxes of its 7 same-size neighbours on the + side of
// some axis; so a rank sends each of its leaves to every later rank whose key
// range meets one of those boxes.  This is p4est_ghost_new's rule in
// cburstedde/p4est (a quadrant goes to the owners of the first and last
// descendants of each of its same-size neighbours, and to the ranks between),
// kept to the + side because ownership of nodes goes by key.  It needs no 2:1
// balance: a node off a leaf's midpoints (an unbalanced octree) still lies in
// those boxes, and its owner gets the leaf and refuses the octree as the
// serial extract does.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "extract/spill_store.h"
#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

// The ghosts this rank (leaves from first_leaf, below stop) owes each rank:
// (*outgoing)[s] is sorted, empty for s <= rank.  start holds each rank's
// first node key and UINT64_MAX at the end (cut_equal_runs).
Status ghost_leaves(BTree& octants, uint64_t first_leaf, uint64_t stop,
                    const std::vector<uint64_t>& start, int rank,
                    std::vector<std::vector<uint64_t>>* outgoing);

// The direction bits the ghosts give the nodes in [start, stop), as runs of
// the spill store (each sorted, one record a key; a key may recur across
// runs).  A run at a time, so that the ghosts' corners cost no more memory
// than the store's cap allows: the last rank's layer holds every leaf on the
// root's far faces.
Status spill_ghost_corners(const std::vector<uint64_t>& ghosts, uint64_t start, uint64_t stop,
                           SpillStore& spills);

}  // namespace weaver
