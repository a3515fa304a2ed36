// The size of an octree before it is built: construct samples the model on a
// coarse grid of cells and sums, per cell, the leaves its material asks for
// (8^(leaf level - cell level)).  The estimate sees the smooth material; fine
// features that only a fine sampling finds (small soft inclusions) add more,
// so it is a guard against runaway sizes (a frequency or domain off by
// orders of magnitude), not a prediction to the percent.
#pragma once

#include <cstdint>
#include <string>

#include "construct/construct.h"
#include "model/velocity_model.h"

namespace weaver {

struct ConstructEstimate {
  double elements = 0;     // leaves of the constructed octree
  double table_bytes = 0;  // its octant table
  double disk_bytes = 0;   // what the run needs free (all stages for `mesh`)
  int sample_level = 0;    // the level of the sampling cells
};

// Samples `model` on cells of about 2^15 per domain (never finer than
// --max-level).  Bytes assume the table's page format.
ConstructEstimate estimate_construct(const ConstructOptions& o, const ConstructPlan& p,
                                     const VelocityModel& model);

// InvalidArgument naming the numbers when the estimate exceeds
// o.max_elements or the free space of the file system holding db_dir.
Status check_construct_fits(const ConstructOptions& o, const ConstructEstimate& e,
                            const std::string& db_dir);

}  // namespace weaver
