// `weaver extract`: the mesh (nodes, their kinds; elements are the leaves)
// from a balanced octant table, by the two-level bucket sort of Tu &
// O'Hallaron (section 4), out of core.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "schema/status.h"

namespace weaver {

struct ExtractOptions {
  // kSort: the two-level bucket sort.  kSearch: the conventional baseline
  // (a node B-tree searched for every element vertex; paper, section 3).
  // Both produce the same node table.
  enum class Algorithm { kSort, kSearch };
  Algorithm algorithm = Algorithm::kSort;
  // The node store of kSearch: the B+tree, as in the paper, or the LSM.
  enum class Store { kBTree, kLsm };
  Store store = Store::kBTree;
  uint64_t memory_bytes = 256ull << 20;
  // Worker threads for the sort algorithm; the output is the same for any count.
  int threads = 1;
  // The level of the high-level buckets; -1 derives it from the budget.
  int bucket_level = -1;
  // Packed leaf pages for the node table (storage/packed_leaf.h); false writes plain ones.
  bool packed = true;
  std::function<void(const char* phase, uint64_t done)> progress;
};

struct ExtractResult {
  uint64_t elements = 0;
  uint64_t nodes = 0, anchored = 0, edge = 0, face = 0;
  int bucket_level = 0;
  uint64_t buckets = 0;
  uint64_t spilled = 0;          // nodal pixels handed to a later bucket
  uint64_t spilled_to_disk = 0;  // of those, the ones that went through a file
  uint64_t node_table_bytes = 0;
  uint64_t search_tree_bytes = 0;  // search: the node B-tree with element codes
};

// Reads the octant table of db_dir, writes its node table.  Refuses an octree
// with overlapping octants or one that is not face+edge 2:1 balanced, naming
// two offending octants; the database is then left as it was.
Status extract_mesh(const std::string& db_dir, const ExtractOptions& options,
                    ExtractResult* result);

}  // namespace weaver
