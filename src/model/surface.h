// The ground surface: elevations (metres, up) on a regular grid in the
// mesh's frame, bilinear between grid points and held at the nearest edge
// value outside the grid.  Where the ground lies over a box is answered
// exactly (a bilinear cell takes its least and greatest value at the corners
// of any rectangle in it), through a pyramid of per-block ranges, so that
// "wholly above the ground" is never a guess.
//
// Sources (`--surface`):
//   flat         none: the domain's top is flat (weaver's meshes as ever)
//   rfile:PATH   an SW4 rfile's block 1 (model/rfile.h): x = i hh, y = j hh
//   asc:PATH     an ESRI ASCII raster (ncols, nrows, xllcorner|xllcenter,
//                yllcorner|yllcenter, cellsize (or dx and dy), optional
//                NODATA_value (default -9999); keywords in any case; rows
//                from north to south, values at cell centres).  Its columns
//                (east) are the mesh's y, its rows (north) the mesh's x, in
//                metres of the mesh's frame; with SurfaceCrs::kLonLat the
//                raster is in degrees and is resampled, at its own spacing,
//                onto the frame's metres through the mesh's GeoFrame.
//   NODATA cells take the value of the nearest valid cell (breadth first
//   over the grid: nearest in steps of one cell, ties by scan order).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "schema/status.h"

namespace weaver {

struct GeoFrame;

enum class SurfaceCrs { kFrame, kLonLat };

class Surface {
 public:
  // A grid of nx x ny points, point (i, j) at (x0 + i dx, y0 + j dy), its
  // elevation z[j * nx + i].
  static std::unique_ptr<Surface> from_grid(int nx, int ny, double x0, double y0, double dx,
                                            double dy, std::vector<float> z);

  // Bytes a surface of nx x ny points holds (the grid and its pyramid).
  static uint64_t bytes_for(uint64_t nx, uint64_t ny) { return nx * ny * 12 + 4096; }

  double elevation(double x, double y) const;
  // The least and greatest ground over the closed rectangle [x0, x1] x [y0, y1].
  void range(double x0, double x1, double y0, double y1, double* lo, double* hi) const;
  // Bounds on them, *lo at most the least and *hi at least the greatest:
  // from at most 2 x 2 blocks of the pyramid, in constant time.
  void loose_range(double x0, double x1, double y0, double y1, double* lo, double* hi) const;
  double highest() const { return max_; }
  double lowest() const { return min_; }
  // The grid's box, and the cells NODATA left (filled from their neighbours).
  double x_lo() const { return x0_; }
  double y_lo() const { return y0_; }
  double x_hi() const { return x0_ + (nx_ - 1) * dx_; }
  double y_hi() const { return y0_ + (ny_ - 1) * dy_; }
  uint64_t filled = 0;
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  double dx() const { return dx_; }
  double dy() const { return dy_; }
  // "" when the grid covers [0, lx] x [0, ly]; else which sides it misses.
  std::string outside(double lx, double ly) const;

 private:
  Surface() = default;
  void build_pyramid();
  // A rectangle in the grid's cells: its span in cell units (clamped to the
  // grid) and the cells it meets.
  struct Span {
    double u0, u1, v0, v1;
    int ci0, ci1, cj0, cj1;
  };
  Span span_of(double x0, double x1, double y0, double y1) const;
  // Range of the bilinear cell (i, j) over its part in the rectangle.
  void cell_range(int i, int j, double x0, double x1, double y0, double y1, double* lo,
                  double* hi) const;
  void block_range(int level, int bi, int bj, int ci0, int ci1, int cj0, int cj1, double x0,
                   double x1, double y0, double y1, double* lo, double* hi) const;
  float at(int i, int j) const { return z_[size_t(j) * nx_ + i]; }

  int nx_ = 0, ny_ = 0;
  double x0_ = 0, y0_ = 0, dx_ = 1, dy_ = 1;
  double min_ = 0, max_ = 0;
  std::vector<float> z_;
  // levels_[l]: the least and greatest of the 2^l x 2^l cells of each block.
  struct Level {
    int w = 0, h = 0;
    std::vector<float> lo, hi;
  };
  std::vector<Level> levels_;
};

struct SurfaceSource {
  std::string text = "flat";  // as the user wrote it
  SurfaceCrs crs = SurfaceCrs::kFrame;
  bool flat() const { return text == "flat"; }
};

// Parses "flat", "rfile:PATH" or "asc:PATH" (InvalidArgument otherwise).
Status parse_surface_source(const std::string& text, SurfaceSource* out);
// Reads the surface (nullptr for flat).  `geo` is the mesh's frame, needed
// for kLonLat; `max_bytes` what it may hold (refused past it, saying so).
Status load_surface(const SurfaceSource& s, const GeoFrame* geo, uint64_t max_bytes,
                    std::unique_ptr<Surface>* out);
// An ESRI ASCII raster's text (for the parser's fuzz target and tests):
// the grid in the raster's own axes, rows from south to north.
struct AscRaster {
  int ncols = 0, nrows = 0;
  double xll = 0, yll = 0;  // of the lower-left cell's centre
  double dx = 0, dy = 0;
  std::vector<float> z;  // row-major from the south row; NODATA as NaN
};
Status parse_asc(const std::string& text, const std::string& what, uint64_t max_cells,
                 AscRaster* out);

}  // namespace weaver
