// Which nodes each part of a partition shares with which other parts: what
// an MPI rank needs to exchange.  Built out of core in two sorts: the (node,
// part) pairs of every element's corners, grouped by node; then, for every
// node that several parts use, a (part, node, other part) triple for each
// ordered pair of them, sorted by part and node, so that the parts can be
// written one after the other, each reading its own triples in node order.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "mesh/mesh_reader.h"
#include "mesh/part_map.h"
#include "sort/external_sort.h"

namespace weaver {

class SharedNodes {
 public:
  Status build(Mesh& mesh, const PartMap& parts, const std::string& scratch_dir, uint64_t memory);
  // The (node, other part) pairs of part p.
  uint64_t count(uint32_t p) const { return counts_[p]; }
  // The next pair of part p, in node order; parts must be read in order,
  // each to its end.
  Status next(uint32_t p, uint64_t* node, uint32_t* other);

 private:
  static constexpr int kNodeBits = 40;
  std::vector<uint64_t> counts_;
  std::unique_ptr<ExternalSorter> by_part_;
};

}  // namespace weaver
