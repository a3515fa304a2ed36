// SW4's rfile: a velocity model with its ground surface, in one binary file
// (SW4's MaterialRfile reads it; pySW4's rfileIO writes it).
//
//   header   int32 magic        1 in the writer's byte order (either is read)
//            int32 precision    4 (float32 values) or 8 (float64)
//            int32 attenuation  1: the material blocks carry Qp and Qs
//            f64   azimuth      of the x axis, degrees clockwise from north
//            f64   lon0, lat0   where x = y = 0 lies (WGS84 degrees)
//            int32 length, then that many bytes: a PROJ string (kept as text)
//            int32 blocks
//   per block, all headers first:
//            f64   hh, hv, z0   horizontal and vertical spacing, the block's
//                               top (z: metres down from sea level)
//            int32 nc, ni, nj, nk
//   then each block's values in C order over (i, j, k, component): i along
//   x, j along y, k down; x = i hh, y = j hh, z = z0 + k hv.
//
// Block 0 is the topography: nc = nk = 1, elevation in metres (up).  Blocks
// 1 and on hold rho, vp, vs (nc = 3) or rho, vp, vs, qp, qs (nc = 5), top to
// bottom; -999 marks "no data" (air, water), which SW4 fills from below.
//
// read_rfile_header checks everything the header promises against the
// file: the data must be exactly as long as the blocks say, the blocks must
// share one horizontal extent and be stacked top to bottom without a gap.
// Errors name the file and what is wrong, in one line.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "schema/status.h"

namespace weaver {

struct RfileBlock {
  double hh = 0, hv = 0, z0 = 0;
  int nc = 0, ni = 0, nj = 0, nk = 0;
  uint64_t offset = 0;  // of the block's first value in the file

  double x_extent() const { return (ni - 1) * hh; }
  double y_extent() const { return (nj - 1) * hh; }
  double bottom() const { return z0 + (nk - 1) * hv; }
  uint64_t values() const { return uint64_t(nc) * ni * nj * nk; }
};

// A coordinate's cell along one axis of a block (points origin + i h, n of
// them) as SW4 finds it: its first point i (trunc(1 + v) on 1-based
// indices, then at least the first point and at most the last but one)
// and the weight w of the next.
struct RfilePlace {
  int i;
  double w;
};
inline int rfile_cell(double v, int last) {
  const double t = std::trunc(v);
  if (!(t > 0)) return 0;
  return t >= last - 1 ? last - 1 : static_cast<int>(t);
}
inline RfilePlace rfile_place(double v, double origin, double h, int n) {
  const int i = rfile_cell((v - origin) / h, n - 1);
  return {i, (v - (i * h + origin)) / h};
}

struct RfileHeader;
// The depths (z down from sea level) whose samples material block b holds,
// as SW4 picks a depth's block: from its top (the first block: from above
// everything) to the next block's top (the last: to below everything).
inline void rfile_block_depths(const RfileHeader& h, size_t b, double* from, double* to);

struct RfileHeader {
  bool swap = false;  // written in the other byte order
  int precision = 4;  // bytes a value
  bool attenuation = false;
  double azimuth = 0, lon0 = 0, lat0 = 0;
  std::string proj;
  std::vector<RfileBlock> blocks;  // [0]: the topography

  bool has_q() const { return blocks.size() > 1 && blocks[1].nc == 5; }
  uint64_t grid_points() const;  // over the material blocks
};

inline void rfile_block_depths(const RfileHeader& h, size_t b, double* from, double* to) {
  *from = b == 1 ? -HUGE_VAL : h.blocks[b].z0;
  *to = b + 1 < h.blocks.size() ? h.blocks[b + 1].z0 : HUGE_VAL;
}

// Parses the header held in bytes [0, n) of a file of file_size bytes.
// `what` names the file in errors.  Corruption for anything wrong; a header
// that runs past n is "truncated" when n is the whole file.
Status parse_rfile_header(const unsigned char* bytes, size_t n, uint64_t file_size,
                          const std::string& what, RfileHeader* out);
// Reads and parses path's header.
Status read_rfile_header(const std::string& path, RfileHeader* out);

// The values of column (i, j) of block b, nk x nc of them (k, then the
// component), as doubles in the machine's order.
Status read_rfile_column(int fd, const RfileHeader& h, int b, int i, int j, double* out);
// The same for `count` columns (i, j), (i, j + 1), ... one after the other
// (they lie so in the file: one read).  REQUIRES: j + count <= the block's nj.
Status read_rfile_columns(int fd, const RfileHeader& h, int b, int i, int j, int count,
                          double* out);
// The same columns' bytes as they lie in the file, each value put in the
// machine's byte order: decode them with rfile_decode.
Status read_rfile_raw(int fd, const RfileHeader& h, int b, int i, int j, int count,
                      std::vector<unsigned char>* raw);
// `count` values of `precision` bytes, in the machine's order, as doubles.
void rfile_decode(int precision, const unsigned char* raw, size_t count, double* out);

// The file's value for "no data".
constexpr double kRfileNoData = -999;

}  // namespace weaver
