// Which nodes each part of a partition shares with which other parts: what
// an MPI rank needs to exchange.  Built out of core in two sorts: the (node,
// part) pairs of every element's corners, grouped by node; then, for every
// node that several parts use, a (part, node, other part) triple for each
// ordered pair of them, sorted by part and node, so that the parts can be
// written one after the other, each reading its own triples in node order.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "export/selection.h"
#include "mesh/mesh_reader.h"
#include "mesh/part_map.h"
#include "sort/external_sort.h"

namespace weaver {

class SharedNodes {
 public:
  Status build(Mesh& mesh, const PartMap& parts, const std::string& scratch_dir, uint64_t memory);
  // The same pairs, of part p only (whose elements `part` selects), found
  // from p's elements alone: for each corner, the leaves around it that have
  // it as a corner too, and their parts.  A lookup only where such a leaf
  // may lie outside p's leaves (part.first, part.end: a run of ids, whose
  // leaves hold the Morton codes from the first one's anchor to the next
  // run's).  For one writer a part (weaver-mpi export): the cost follows the
  // part's surface, not the mesh.
  Status build_part(Mesh& mesh, const PartMap& parts, const Selection& part,
                    const std::string& scratch_dir, uint64_t memory);
  // The (node, other part) pairs of part p.
  uint64_t count(uint32_t p) const { return counts_[p]; }
  // The next pair of part p, in node order; parts must be read in order,
  // each to its end.
  Status next(uint32_t p, uint64_t* node, uint32_t* other);

 private:
  static constexpr int kNodeBits = 40;
  struct KnownLeaf {
    bool valid = false;
    uint64_t morton = 0;
    int span_bits = 0;  // the leaf holds the pixels whose codes agree above these bits
    Octant octant;
    uint32_t part = 0;
  };
  Status leaf_at(Mesh& mesh, const PartMap& parts, uint64_t pm, const KnownLeaf** out);
  std::array<KnownLeaf, 32> known_;
  size_t next_known_ = 0;
  // The parts other than `part` of the leaves that have node c as a corner.
  Status other_parts_at(Mesh& mesh, const PartMap& parts, uint32_t part, Coord c, uint64_t run_lo,
                        uint64_t run_hi, std::vector<uint32_t>* others);
  std::vector<uint64_t> counts_;
  std::unique_ptr<ExternalSorter> by_part_;
};

}  // namespace weaver
