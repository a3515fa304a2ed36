// `weaver model import`: a velocity model into the model table of a database
// (modeldb/model_table.h), by sorted append through MaterialMerger, in
// bounded memory whatever the model's size.
//
//   etree:FILE   the original etree library's files (CVM etrees, the USGS Bay
//                Area model): its leaves, Vp, Vs, density (and Qp, Qs where
//                the schema has them) found by name; interior octants skipped
//   grid:FILE    a weaver-grid 1 file, read a block of rows at a time: one
//                octant per grid point (edge: the smallest spacing, centred
//                on the point), trilinear where the spacings differ
//   layers:FILE  a 1-D layer table (model/layer_table.h): a column of
//                cells, the model the same across (x and y extents 0)
//   xyz:FILE     ASCII x y z vp vs rho lines in any order (model/xyz_grid.h):
//                written out as a grid in the database's directory (out of
//                core), then imported as grid:
//
// Refuses (one line, naming the file and the record) a schema without the
// fields, octants finer than weaver's 20 levels, a non-positive or
// non-finite velocity or density; the database is left as it was.
#pragma once

#include <cstdint>
#include <string>

#include "db/octant_table.h"
#include "modeldb/model_table.h"
#include "schema/status.h"
#include "util/memory_budget.h"
#include "util/progress.h"

namespace weaver {

struct ModelImportOptions {
  std::string from;        // "etree:FILE", "grid:FILE", "layers:FILE", "xyz:FILE" or "rfile:FILE"
  double tolerance = 0;    // relative; 0 merges exactly equal siblings only
  double root_edge_m = 0;  // etree: the root's edge when its metadata does not say
  MemoryBudget memory;
  bool packed = true;
  // rfile: threads that sample the file (the table the same for any count),
  // and the most cells a subtree of the work holds (0: from the budget).
  int threads = 1;
  uint64_t rfile_task_cells = 0;
  // Octants stored so far (the fraction unknown: -1), now and then.
  ProgressFn progress;
};

struct ModelImportResult {
  uint64_t read = 0;     // octants or grid points taken from the source
  uint64_t octants = 0;  // stored, after merging
  LevelCounts levels{};
  ModelInfo info;
  uint64_t table_bytes = 0;
};

Status import_model(const std::string& db_dir, const ModelImportOptions& options,
                    ModelImportResult* result);

}  // namespace weaver
