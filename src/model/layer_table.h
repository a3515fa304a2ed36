// A 1-D layered velocity model, as seismologists publish them (a
// Hadley-Kanamori style table): one line a layer,
//
//   # top_depth  vp    vs    rho   [qp   qs]
//   0            5500  3180  2400
//   5500         6300  3640  2670
//   16000        6700  3870  2800
//
// depths in metres (down), velocities in m/s, density in kg/m^3.  A layer
// reaches from its top to the next layer's; the last is a half-space.  The
// first top must be 0 (the surface), tops strictly increase, velocities and
// density are positive and finite, Q (on every line or none) not negative.
// Blank lines and '#' comments are skipped.
#pragma once

#include <string>
#include <vector>

#include "model/material_merge.h"
#include "schema/status.h"

namespace weaver {

struct Layer {
  double top_m = 0;
  ModelValues values{};  // vp, vs, rho[, qp, qs]
};

struct LayerTable {
  std::vector<Layer> layers;
  bool has_q = false;
};

// Parses the table's text; `name` (the file) starts each error, with the
// line: "FILE:3: tops must increase (5500 after 16000)".
Status parse_layer_table(const std::string& text, const std::string& name, LayerTable* out);
Status read_layer_table(const std::string& path, LayerTable* out);

}  // namespace weaver
