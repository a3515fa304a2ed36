// A user's velocity model on a regular grid, trilinearly interpolated.
//
// File format (text header, then binary data):
//   weaver-grid 1
//   NX NY NZ          grid points per axis (each >= 2)
//   X0 Y0 Z0          position of point (0,0,0) in metres (z = depth, down)
//   DX DY DZ          spacing in metres (each > 0)
//   <newline ends the header; then NX*NY*NZ records, x fastest, then y,
//    then z; each record is Vp, Vs, rho as little-endian float32>
// Points outside the grid take the value at the nearest grid boundary.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "model/velocity_model.h"

namespace weaver {

Status load_grid_model(const std::string& path, std::unique_ptr<VelocityModel>* out);

// Writes a grid file (for tests and for users converting their models).
struct GridSpec;
// Reads and checks a grid file's header (and that the file holds exactly
// the data it promises): its spec and where the float32 records start.
Status read_grid_header(const std::string& path, GridSpec* spec, uint64_t* data_offset);

struct GridSpec {
  int nx = 2, ny = 2, nz = 2;
  double x0 = 0, y0 = 0, z0 = 0, dx = 1, dy = 1, dz = 1;
};
Status write_grid_model(const std::string& path, const GridSpec& spec,
                        const std::vector<Material>& values);

}  // namespace weaver
