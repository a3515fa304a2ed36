// The mesh invariants of verify.h, given the octant and node tables.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>

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

// The node check by derivation: the node records extraction derives again
// from the octants (extract.h, derive_nodes), compared with the stored
// table in key order, a bucket at a time, so that no node is looked for.
// A stored node that differs, or that no element has as a corner, is then
// checked alone as check_node_range checks it, for the message that says
// why; a derived node the table lacks is named; every dangling node's
// anchors are looked up (a chain of dependencies is a problem).  Adds the
// report's counts.  REQUIRES: the octree is 2:1 balanced.
class NodeStreamCheck {
 public:
  NodeStreamCheck(BTree& octants, BTree& nodes, Problems& problems, VerifyReport* report);
  ~NodeStreamCheck();
  Status open();  // before the first compare
  // The next derived nodes, in key order.
  Status compare(const uint64_t* keys, const std::byte* kinds, size_t n);
  // After the last: the stored nodes past them; the element and corner counts.
  Status finish(uint64_t elements);

 private:
  struct State;
  Status stored_differs();
  Status next_stored();

  BTree& nodes_;
  Problems& problems_;
  VerifyReport* report_;
  std::unique_ptr<State> state_;
  uint64_t missing_corners_ = 0;  // of elements, at derived nodes not stored
};

// After every node: each element's 8 corners were found at nodes (the
// report's counts, summed over the ranges), or the first element that
// lacks one is named.
Status check_corner_total(BTree& octants, BTree& nodes, Problems& problems, VerifyReport* report);

}  // namespace weaver
