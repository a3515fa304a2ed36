// `weaver slice`: a cross-section of the mesh on an axis-aligned plane, as
// a PNG or SVG picture: the elements the plane cuts, outlined and filled by
// a field (level, vp, vs, rho) on a colour scale, with a colour bar, axes
// in km (or m) and, on request, the dangling nodes that lie on the plane.
// Out of core: two range queries over the elements the plane cuts (one for
// the extent and the colour scale, one to draw); memory is the picture.
#pragma once

#include <cstdint>
#include <string>

#include "schema/status.h"
#include "util/memory_budget.h"

namespace weaver {

struct SliceOptions {
  int axis = 2;     // the plane's normal: 0 x, 1 y, 2 z
  double at_m = 0;  // where it crosses that axis, in metres (see at_ticks)
  bool at_is_ticks = false;
  // A z plane given as an elevation (metres up): z = the top's elevation
  // minus at_m, for a mesh built under a ground (slice --z elevation).
  bool at_is_elevation = false;
  std::string color = "level";  // level, vp, vs, rho
  int width = 1600;             // pixels, margins and colour bar included
  bool danglings = false;       // mark the dangling nodes on the plane
  // Only the part of the plane from (a0, b0) to (a1, b1), in the plane's two
  // axes (x, y for a z plane; y, z for x; x, z for y) and --at's units.
  bool has_region = false;
  double region[4] = {0, 0, 0, 0};
  MemoryBudget memory;
};

struct SliceResult {
  uint64_t elements = 0;    // cut by the plane
  uint64_t danglings = 0;   // marked
  double min = 0, max = 0;  // of the field over those elements
  int width = 0, height = 0;
  uint32_t at_ticks = 0;  // the plane
};

// Writes the picture to out (".png" or ".svg" decides) through a temporary
// file.  InvalidArgument for a plane outside the domain, a field the mesh
// lacks, or a width out of 200..20000.
Status render_slice(const std::string& db, const SliceOptions& o, const std::string& out,
                    SliceResult* r);

}  // namespace weaver
