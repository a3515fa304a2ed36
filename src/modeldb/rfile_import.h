// An SW4 rfile (model/rfile.h) into a model database (`weaver model import
// --from rfile:FILE`): an octree over the file's box (x, y from 0; z from
// the first material block's top, metres down from sea level) whose leaves
// are each block's cells, as fine as its smaller spacing rounded down to a
// power of two of the tick, each holding the file's value at its centre as
// SW4 samples it (trilinear, -999 filled from below: model/rfile_model.h).
// Equal siblings merge (model/material_merge.h).  A database answers
// piecewise constant values where SW4 interpolates: within one cell of the
// file's own spacing of them, never past the nearest grid values; `weaver
// mesh --model rfile:FILE` samples the file itself and is exact.
#pragma once

#include <memory>
#include <string>

#include "model/material_merge.h"
#include "model/rfile_model.h"
#include "modeldb/import_source.h"
#include "modeldb/model_table.h"
#include "util/memory_budget.h"

namespace weaver {

struct RfilePlan {
  std::unique_ptr<RfileModel> model;
  double root_m = 0;
};

// Opens and checks the file (its column caches for up to `threads`
// threads within `memory`, at most 8 MB a thread); sets the model's
// placement in *info.
Status plan_rfile(const std::string& path, MemoryBudget memory, int threads, RfilePlan* p,
                  ModelInfo* info);

// How the import runs: the octree is cut into subtrees of about
// task_cells cells at most (where the blocks' spacings allow), sampled on
// `threads` threads and emitted in key order, so that the table is the
// same for any count.
// Each subtree's cells are merged on its thread by a merger like `out`
// (tolerance, fields), whose entries `out` takes on.
struct RfileImportRun {
  int threads = 1;
  uint64_t task_cells = 1 << 18;
  double tolerance = 0;
  int fields = 3;
};
// The cells in key order into *out; *read counts them.
Status import_rfile(const RfilePlan& p, const ModelInfo& info, const RfileImportRun& run,
                    uint64_t* read, MaterialMerger* out);

}  // namespace weaver
