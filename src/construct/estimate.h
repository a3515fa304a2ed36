// The size of an octree before it is built: construct samples the model on a
// coarse grid of cells and sums, per cell, the leaves its material asks for
// (8^(leaf level - cell level)).  The estimate sees the smooth material; fine
// features that only a fine sampling finds (small soft inclusions) add more,
// so it is a guard against runaway sizes (a frequency or domain off by
// orders of magnitude), not a prediction to the percent.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "construct/construct.h"
#include "model/velocity_model.h"

namespace weaver {

// Disk: what the run needs free (its tables, and for `mesh` the node and
// boundary tables and the scratch beside them), at the worst packing of
// materials (every leaf's its own) and at the best (neighbours share them),
// which the estimate cannot tell apart: a run that cannot fit even at the
// best is refused; one that fits at the best only is said to risk it.
struct ConstructEstimate {
  double elements = 0;          // leaves of the constructed octree
  double table_bytes = 0;       // its octant table, at the worst packing
  double disk_bytes = 0;        // at the worst packing
  double least_disk_bytes = 0;  // at the best
  int sample_level = 0;         // the level of the sampling cells
};

// The estimate a plan carries (plan_construct made it).
ConstructEstimate planned_estimate(const ConstructPlan& p);

// Free bytes on the file system of dir (or of its nearest existing parent);
// -1 if it cannot be told.
double free_disk_bytes(const std::string& dir);

// The estimate spread along the Z-order: how much of the octree lies before
// a key.  Construct's progress reports fraction_before(last leaf written):
// it moves at the pace of the model's material (fast through rock, slow
// through sediment) and reaches 1 exactly when the descent ends.
class ZOrderShare {
 public:
  void add(uint64_t cell_key, double leaves);  // any order
  void finish();                               // sorts; REQUIRES: after the adds
  // The share of the estimate in cells whose keys are below key.
  double fraction_before(uint64_t key) const;

 private:
  std::vector<std::pair<uint64_t, double>> cells_;  // key, estimated leaves up to it
  double total_ = 0;
};

// Samples `model` on cells of about 2^15 per domain (never finer than
// --max-level).  Bytes assume the table's page format.  With `share`, also
// records each sampled cell's leaves there.
ConstructEstimate estimate_construct(const ConstructOptions& o, const ConstructPlan& p,
                                     const VelocityModel& model, ZOrderShare* share = nullptr);

// InvalidArgument naming the numbers when the estimate exceeds
// o.max_elements, or when even its least disk exceeds the free space of the
// file system holding db_dir.
Status check_construct_fits(const ConstructOptions& o, const ConstructEstimate& e,
                            const std::string& db_dir);

}  // namespace weaver
