// A velocity model on a regular grid as ASCII lines `x y z vp vs rho`, in
// any order (the SPECFEM3D tomography style): metres, z depth (down), m/s
// and kg/m^3, whitespace-separated, blank lines and '#' comments skipped.
// Every grid point appears exactly once; the grid is the product of the
// distinct x, y and z values, each axis evenly spaced.
//
// Read in two streaming passes (modeldb/model_import.cc): scan_xyz_grid
// finds the grid (only the distinct coordinates are held: at most 100000 an
// axis, as for weaver-grid files), for_each_xyz_point hands over each point
// with its grid index.
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "model/grid_model.h"
#include "schema/status.h"

namespace weaver {

struct XyzGrid {
  GridSpec spec;        // nx, ny, nz, origin and spacing
  uint64_t points = 0;  // lines with a point
};

// Pass 1: the grid; refuses a malformed line, a non-positive or non-finite
// value, uneven spacing, fewer than 2 values on an axis, and a line count
// that is not nx * ny * nz (each error names the file, and the line).
Status scan_xyz_grid(const std::string& path, XyzGrid* out);

// Pass 2: each point, with its index (x fastest, then y, then z) on `grid`.
using XyzPointFn = std::function<Status(uint64_t index, const float values[3])>;
Status for_each_xyz_point(const std::string& path, const XyzGrid& grid, const XyzPointFn& fn);

}  // namespace weaver
