// What the importers of each source (modeldb/model_import.h) share: the sink
// their octants go to, in key order, and the check of every record's values.
// And the simplest source, a 1-D layer table (model/layer_table.h).
#pragma once

#include <cfloat>
#include <functional>
#include <string>
#include <vector>

#include "model/layer_table.h"
#include "model/material_merge.h"
#include "modeldb/model_table.h"
#include "schema/octant.h"
#include "schema/status.h"

namespace weaver {

using ModelEmit = std::function<Status(const Octant&, const ModelValues&)>;

// The first of the first `fields` values out of range (velocities and
// density positive, Q not negative, all finite), or -1.  Cheap: it runs on
// every record.
int bad_model_field(const ModelValues& v, int fields);
// Whether bad_model_field finds nothing, without a branch a field: the
// check of every sampled cell (NaN fails the compares).
inline bool model_fields_ok(const ModelValues& v, int fields) {
  int ok = 1;
  for (int f = 0; f < 3; ++f) ok &= int(v[f] > 0) & int(v[f] <= FLT_MAX);
  for (int f = 3; f < fields; ++f) ok &= int(v[f] >= 0) & int(v[f] <= FLT_MAX);
  return ok != 0;
}
// The error for a record whose field f is out of range; `what` names it.
Status bad_model_value(const std::string& what, const ModelValues& v, int f);

// A layer table as a column of octants at x = y = 0 down the z axis, the
// model the same across (extent 0 in x and y, see ModelInfo): each layer's
// depth range as aligned power-of-two runs of ticks.  The tick divides the
// tops' common divisor (to 1 mm) where that leaves at most 2^19 of them to
// the deepest top: the boundaries are exact; otherwise the deepest top is
// half the root's depth and each top is rounded to the nearest tick (within
// deepest / 2^20: 3 cm for a 32 km Moho).  Below the deepest top the last
// layer fills the root, and clamping continues it.
struct LayerPlan {
  LayerTable table;
  std::vector<uint32_t> tops;  // ticks
  bool exact = false;
};
Status plan_layers(const std::string& path, LayerPlan* plan, ModelInfo* info);
Status import_layers(const LayerPlan& plan, uint64_t* read, const ModelEmit& emit);

}  // namespace weaver
