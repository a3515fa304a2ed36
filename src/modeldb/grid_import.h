// Grid sources of the model import (modeldb/model_import.h): a weaver-grid 1
// file, read a block of rows at a time (never whole), one octant per grid
// point; and an xyz file (model/xyz_grid.h), first written out as a grid.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "model/grid_model.h"
#include "model/material_merge.h"
#include "model/xyz_grid.h"
#include "modeldb/import_source.h"
#include "util/memory_budget.h"

namespace weaver {

struct GridPlan {
  GridSpec s;
  uint64_t data = 0;
  double edge_m = 0;
  std::array<uint32_t, 3> cells{};  // octants a side, one per grid point
  int level = 0;                    // of the octants
};

// Reads the grid's header: octants of the smallest spacing, centred on the
// points; sets the model's placement in *info.
Status plan_grid(const std::string& path, GridPlan* g, ModelInfo* info);
// Emits the grid's octants in key order, trilinear where spacings differ.
// Blocks of up to 128 points a side as `memory` allows, each merged in
// memory (model/block_merge.h) before the merger sees it.
Status import_grid(const GridPlan& g, const std::string& path, MemoryBudget memory, uint64_t* read,
                   MaterialMerger& merger);

// Writes the xyz file's points as a weaver-grid 1 file at grid_path, each
// where its index says (the file is made sparse first, so any order of
// lines costs only the page cache, not our memory).  A grid point no line
// gave is an error naming its coordinates; the grid file is removed then.
Status write_xyz_as_grid(const std::string& xyz_path, const XyzGrid& grid,
                         const std::string& grid_path);

}  // namespace weaver
