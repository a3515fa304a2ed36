// Bounds on an rfile's Vs over a box (VelocityModel::vs_bounds), so that
// construct settles most octants without sampling the file: for each
// material block, the least and greatest Vs (as filled: -999 taken from
// below) of the grid points of each tile of kTile x kTile x kTile cells,
// the points on a tile's far faces included.  A point's value is SW4's
// trilinear blend of its cell's eight corners, so it lies within the range
// of the tiles that hold the cells a box meets, in the blocks it meets.
// Built once, in one pass over every column of the file (a few MB: a
// thousandth of the grid).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "model/rfile.h"

namespace weaver {

class RfileVsTiles {
 public:
  static constexpr int kTile = 4;
  // Tiles a bound looks at, at most: a larger box is left to sampling.
  static constexpr uint64_t kMostTiles = 512;

  // column(b, i, j): column (i, j) of block b, filled, nk x nc values
  // (valid until the next call).
  using Column = std::function<const double*(int b, int i, int j)>;
  void build(const RfileHeader& h, const Column& column);

  // Bounds on the Vs at() gives at every point of the closed box [lo, hi]
  // (x, y from 0, z down from sea level; held to the file's box as at()
  // holds points); false where the box meets more than kMostTiles tiles.
  bool bounds(const RfileHeader& h, const double lo[3], const double hi[3], float* vs_lo,
              float* vs_hi) const;

 private:
  struct Block {
    int n[3] = {0, 0, 0};  // tiles along i, j, k
    std::vector<float> lo, hi;
    size_t at(int ti, int tj, int tk) const { return (size_t(tk) * n[1] + tj) * n[0] + ti; }
  };
  std::vector<Block> blocks_;  // material block b at b - 1
};

}  // namespace weaver
