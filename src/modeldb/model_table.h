// The model table: a velocity model stored as an octree of materials in
// weaver's own storage.  Key = packed octant key (schema/octant.h); payload
// material_schema: vp, vs, rho and, where the source has them, qp, qs (f32,
// m/s and kg/m^3).
// A point's material is the octant holding it: the floor of its pixel key
// (the aggregate hit).  The leaves need not fill the root: a point the model
// does not cover is clamped into the model's box first (ModelInfo::extent_m).
//
// Model coordinates are metres from the model's origin, z depth (down): the
// frame construct's --domain and the queries use.
#pragma once

#include <array>
#include <string>

#include "db/model_table_name.h"
#include "model/etree_file.h"
#include "model/velocity_model.h"
#include "schema/record_schema.h"
#include "schema/status.h"

namespace weaver {

struct ModelInfo {
  double tick_m = 1;                           // metres per tick (the root's edge / 2^20)
  std::array<double, 3> origin_m = {0, 0, 0};  // where tick 0 is, in model metres
  // The model's box, from its origin; 0 on an axis the model does not vary
  // along (a layered model's x and y), where every point is inside.
  std::array<double, 3> extent_m = {0, 0, 0};
  bool has_q = false;
  std::string source;  // "etree FILE", "grid FILE"
  // Longitude, latitude of the origin and azimuth of x (degrees) where the
  // source says; "" otherwise.
  std::string geo;
  std::string producer;  // the source's own metadata text, as far as it goes
};

// Metadata text (";"-separated key=value; units_from_metadata reads it too).
std::string model_info_to_metadata(const ModelInfo& info);
void model_info_from_metadata(const std::string& metadata, ModelInfo* info);

// What an etree's application metadata says of its size and place.  The
// three forms in use: createcvm's "LABASE latfrom .. lonfrom .. xsize ..",
// UCVM's CMU form "Title:.. Author:.. Date:.. 3 schema lat lon xdim ydim
// depth zdim xticks yticks zticks" and UCVM's "SCEC_CVM_V1|...|proj|lon,lat,
// depth|rot|dims|ticks".  Sets *root_edge_m (the 2^31-tick root's edge),
// extent and geo; NotFound naming the text when it is none of these.
Status etree_placement(const std::string& app_metadata, double* root_edge_m, ModelInfo* info);

}  // namespace weaver
