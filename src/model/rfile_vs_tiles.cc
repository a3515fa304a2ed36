#include "model/rfile_vs_tiles.h"

#include <algorithm>
#include <cmath>

namespace weaver {
namespace {

// The tiles (at most two) whose points along an axis include point p: the
// one it starts, and the one before where it is that one's far face.
int tiles_of_point(int p, int tiles, int out[2]) {
  constexpr int t = RfileVsTiles::kTile;
  int count = 0;
  if (p / t < tiles) out[count++] = p / t;
  if (p % t == 0 && p > 0) out[count++] = p / t - 1;
  return count;
}

float down(double v) {
  const float f = static_cast<float>(v);
  return double(f) > v ? std::nextafter(f, -HUGE_VALF) : f;
}

float up(double v) {
  const float f = static_cast<float>(v);
  return double(f) < v ? std::nextafter(f, HUGE_VALF) : f;
}

}  // namespace

void RfileVsTiles::build(const RfileHeader& h, const Column& column) {
  blocks_.clear();
  for (size_t b = 1; b < h.blocks.size(); ++b) {
    const RfileBlock& k = h.blocks[b];
    Block t;
    const int points[3] = {k.ni, k.nj, k.nk};
    for (int a = 0; a < 3; ++a) t.n[a] = (std::max(1, points[a] - 1) + kTile - 1) / kTile;
    const size_t tiles = size_t(t.n[0]) * t.n[1] * t.n[2];
    std::vector<double> lo(tiles, HUGE_VAL), hi(tiles, -HUGE_VAL);
    int ti[2] = {}, tj[2] = {}, tk[2] = {};
    for (int i = 0; i < k.ni; ++i) {
      const int ci = tiles_of_point(i, t.n[0], ti);
      for (int j = 0; j < k.nj; ++j) {
        const int cj = tiles_of_point(j, t.n[1], tj);
        const double* col = column(int(b), i, j);
        for (int z = 0; z < k.nk; ++z) {
          const double vs = col[size_t(z) * k.nc + 2];
          const int ck = tiles_of_point(z, t.n[2], tk);
          for (int a = 0; a < ci; ++a)
            for (int c = 0; c < cj; ++c)
              for (int d = 0; d < ck; ++d) {
                const size_t at = t.at(ti[a], tj[c], tk[d]);
                lo[at] = std::min(lo[at], vs), hi[at] = std::max(hi[at], vs);
              }
        }
      }
    }
    // Rounded outwards: at() rounds its blend, which lies between them, to
    // a float between these.
    t.lo.resize(tiles), t.hi.resize(tiles);
    for (size_t q = 0; q < tiles; ++q) t.lo[q] = down(lo[q]), t.hi[q] = up(hi[q]);
    blocks_.push_back(std::move(t));
  }
}

bool RfileVsTiles::bounds(const RfileHeader& h, const double lo[3], const double hi[3],
                          float* vs_lo, float* vs_hi) const {
  const RfileBlock& top = h.blocks[1];
  const double x_end = h.blocks[0].x_extent(), y_end = h.blocks[0].y_extent();
  const double z_top = top.z0, z_end = h.blocks.back().bottom();
  const double x0 = std::clamp(lo[0], 0.0, x_end), x1 = std::clamp(hi[0], 0.0, x_end);
  const double y0 = std::clamp(lo[1], 0.0, y_end), y1 = std::clamp(hi[1], 0.0, y_end);
  const double z0 = std::clamp(lo[2], z_top, z_end), z1 = std::clamp(hi[2], z_top, z_end);
  float least = HUGE_VALF, most = -HUGE_VALF;
  uint64_t looked = 0;
  for (size_t b = 1; b < h.blocks.size(); ++b) {
    // A depth is in block b from its top (the first block: from anywhere)
    // to the next one's top, as RfileModel finds its block.
    const RfileBlock& k = h.blocks[b];
    double from, to;
    rfile_block_depths(h, b, &from, &to);
    if (z1 < from || z0 >= to) continue;
    const Block& t = blocks_[b - 1];
    const int first[3] = {rfile_place(x0, 0, k.hh, k.ni).i / kTile,
                          rfile_place(y0, 0, k.hh, k.nj).i / kTile,
                          rfile_place(std::max(z0, from), k.z0, k.hv, k.nk).i / kTile};
    const int last[3] = {rfile_place(x1, 0, k.hh, k.ni).i / kTile,
                         rfile_place(y1, 0, k.hh, k.nj).i / kTile,
                         rfile_place(std::min(z1, to), k.z0, k.hv, k.nk).i / kTile};
    uint64_t tiles = 1;
    for (int a = 0; a < 3; ++a) tiles *= uint64_t(std::min(last[a], t.n[a] - 1) - first[a] + 1);
    looked += tiles;
    if (looked > kMostTiles) return false;
    for (int tk = first[2]; tk <= std::min(last[2], t.n[2] - 1); ++tk)
      for (int tj = first[1]; tj <= std::min(last[1], t.n[1] - 1); ++tj)
        for (int ti = first[0]; ti <= std::min(last[0], t.n[0] - 1); ++ti) {
          least = std::min(least, t.lo[t.at(ti, tj, tk)]);
          most = std::max(most, t.hi[t.at(ti, tj, tk)]);
        }
  }
  if (looked == 0) return false;
  *vs_lo = least, *vs_hi = most;
  return true;
}

}  // namespace weaver
