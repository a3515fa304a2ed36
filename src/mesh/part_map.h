// The part of each element of a partitioned mesh, as runs of consecutive
// element ids (db/partition_table.h): read from the partition table, or held
// in memory for a partition not stored (a space-filling-curve one, which is
// a run a part).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "schema/status.h"
#include "storage/btree.h"

namespace weaver {

struct PartRun {
  uint64_t first;  // element id where the run starts
  uint32_t part;
};

class PartMap {
 public:
  // Runs in memory, ascending firsts, the first at element 0.
  static PartMap of_runs(std::vector<PartRun> runs, uint32_t parts);
  // The runs of a partition table (which the map reads, and must outlive it).
  static Status of_table(BTree& table, uint32_t parts, PartMap* out);

  uint32_t parts() const { return parts_; }
  // The part of element id.
  Status part_of(uint64_t id, uint32_t* part) const;

 private:
  uint32_t parts_ = 0;
  std::vector<PartRun> runs_;  // in memory; or
  BTree* table_ = nullptr;     // floor lookups in the table
};

}  // namespace weaver
