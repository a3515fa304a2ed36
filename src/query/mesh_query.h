// Queries over an extracted mesh: elements and nodes by id or coordinate.
#pragma once

#include <array>
#include <cstdint>

#include "mesh/mesh_reader.h"
#include "schema/node.h"
#include "schema/octant.h"
#include "schema/status.h"
#include "storage/btree.h"
#include "util/memory_budget.h"

namespace weaver {

// Where a query's memory goes: the shares of --memory.
struct QueryMemory {
  explicit QueryMemory(MemoryBudget budget) : plan(budget) {
    // Each question is a few root-to-leaf paths in each table: the pools
    // only cache them between the questions of one process.
    octant_pool = plan.take("octant table pool", 1, 2);
    node_pool = plan.take("node table pool", 1, 2);
  }

  MemoryPlan plan;
  uint64_t octant_pool = 0, node_pool = 0;
};

struct ElementInfo {
  uint64_t id = 0;
  Octant octant;
  bool has_nodes = false;           // false when no node table exists yet
  std::array<uint64_t, 8> nodes{};  // node ids of corners 0..7
};

using NodeInfo = MeshNode;  // id, coordinate, kind, anchor ids

// The element with this id (its rank in key order); nodes may be null.
// InvalidArgument if the id is past the last element.
Status element_by_id(BTree& octants, BTree* nodes, uint64_t id, ElementInfo* out);
// The element's node ids, for an element found some other way.
Status element_nodes(BTree& nodes, const Octant& o, std::array<uint64_t, 8>* ids);
Status node_by_id(BTree& nodes, uint64_t id, NodeInfo* out);
// *found is false when no node sits at c.  InvalidArgument if c is beyond the
// far side of the root.
Status node_at(BTree& nodes, Coord c, NodeInfo* out, bool* found);

}  // namespace weaver
