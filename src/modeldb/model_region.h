// The model octants around one box, decoded into memory, with a raster that
// finds the octant holding a pixel in a few loads.  Construct asks up to 125
// points of the model for every octant it splits; a B+tree floor for each
// (hundreds of ns) made construct from a model database 12x slower than from
// an analytic model.  A construct subtree's points all lie in its closed box,
// so DbModel loads that box once (a few range scans of the model table) and
// answers the subtree's points from here.
//
// Loading: the box is covered by aligned model-space cells of at least a
// quarter of its size (at most 5 a side); each cell is one floor (a model
// octant holding the whole cell) or one cursor scan of the cell's subtree.
// Records come in key order, so the octants are sorted and disjoint.
//
// The raster: cells of 2^shift pixels, aligned, over the box; shift is the
// finest model octant's edge in the box, coarsened until the raster has at
// most max_cells_.  A cell holds the index of the one octant covering it, or
// kHole (no octant meets it), or kMixed (smaller octants share it: a binary
// search of the sorted keys answers).
//
// Vs bounds: each cell's least and greatest Vs (of the octants meeting it,
// 0 where a hole is, as DbModel answers a hole), then a pyramid of 2 x 2 x 2
// reductions above, so that the bounds over any box come from at most 27
// entries (the level where the box spans at most 3 a side): wider than the
// box's own by up to about half its size, never narrower.  (At most 8, 2 a
// side, were wider by up to its size: an octant's closed box meets the
// cells past its far sides, so fewer octants settled by the bounds alone
// and fewer blocks of one level were found; construct from a model
// database took 1.11x the time of 27.)
#pragma once

#include <cstdint>
#include <vector>

#include "model/material_merge.h"
#include "schema/octant.h"
#include "schema/status.h"
#include "storage/btree_cursor.h"

namespace weaver {

class BTree;

class ModelRegion {
 public:
  static constexpr int32_t kHole = -1;
  static constexpr int32_t kMixed = -2;
  // The raster's most cells: kMinCells unless set_max_cells says more (up
  // to kMaxCells, as DbModel's budget allows; kMinCells is the least it
  // gives).  A cell costs about kBytesPerCell: its raster entry (4), its Vs
  // range (8) and the pyramid's share above it (8/7).
  static constexpr uint64_t kMinCells = uint64_t{1} << 15;
  static constexpr uint64_t kMaxCells = uint64_t{1} << 20;
  static constexpr uint64_t kBytesPerCell = 14;
  // A finer raster answers more points without searching a mixed cell's
  // octants, but costs more to build at every load.
  void set_max_cells(uint64_t cells) { max_cells_ = cells; }
  // The model table's leaves kept decoded between loads, shared with the
  // other threads' regions (BTreeCursor::keep_decoded): neighbouring boxes
  // read the same leaves.  Null keeps none.
  void set_decoded_leaves(DecodedLeaves* leaves) { decoded_ = leaves; }

  // Loads the octants of `table` (model records of record_bytes) that meet
  // the pixel box [lo, hi] (bounds included).  Gives up (loaded() false,
  // Ok) past max_octants, so memory stays bounded wherever the model is
  // dense; the caller then asks the table.
  Status load(BTree& table, Coord lo, Coord hi, size_t record_bytes, size_t max_octants);
  void clear();

  bool loaded() const { return loaded_; }
  // Whether pixel p lies in the loaded box.
  bool covers(Coord p) const {
    return loaded_ && p.x - lo_.x <= hi_.x - lo_.x && p.y - lo_.y <= hi_.y - lo_.y &&
           p.z - lo_.z <= hi_.z - lo_.z;
  }
  // The raster cell of pixel p on each axis: cell(x, y, z) needs all three.
  // REQUIRES: covers(p).
  uint32_t cell_x(uint32_t x) const { return (x >> shift_) - base_[0]; }
  uint32_t cell_y(uint32_t y) const { return (y >> shift_) - base_[1]; }
  uint32_t cell_z(uint32_t z) const { return (z >> shift_) - base_[2]; }
  // The octant holding pixel p, given its cells: an index, or kHole.
  int32_t find(Coord p, uint32_t cx, uint32_t cy, uint32_t cz) const {
    return find_in_cell(cell_index(cx, cy, cz), p);
  }
  int32_t find(Coord p) const { return find(p, cell_x(p.x), cell_y(p.y), cell_z(p.z)); }
  // The Vs at pixel p (0 in a hole), given its cells: the cell's Vs range
  // where it is one value (every cell but a mixed one whose octants
  // differ), the octant's values read only where it is not.  (The values
  // are in key order, the cells by row: read for each point of construct's
  // lattices, they were a third of its time in them, in cache misses.)
  float vs_at(Coord p, uint32_t cx, uint32_t cy, uint32_t cz) const {
    const size_t c = cell_index(cx, cy, cz);
    const VsRange& r = pyramid_[0].ranges[c];
    return r.lo == r.hi ? r.lo : octant_vs(find_in_cell(c, p));
  }

  // A lattice of pixels, every point covered: its points' pixels (p[a][i]
  // on axis a) and raster cells (c[a][i]), n a side; point (i, j, k) is
  // answered at index (k * n + j) * n + i.  vs_at, or find, of every
  // point with the raster's layout read once a lattice, not once a point
  // (construct asks a lattice for every octant it judges).
  static constexpr int kLatticeMost = 8;  // the most points a side
  struct Lattice {
    const uint32_t* p[3];
    const uint32_t* c[3];
    int n;
  };
  void vs_on_lattice(const Lattice& l, float* out) const;
  void find_on_lattice(const Lattice& l, int32_t* out) const;

  // Where cell (cx, cy, cz) is in the raster and the pyramid's level 0.
  size_t cell_index(uint32_t cx, uint32_t cy, uint32_t cz) const {
    return (size_t{cz} * dims_[1] + cy) * dims_[0] + cx;
  }

  // Bounds on the Vs at every pixel of the box [lo, hi] (bounds included;
  // a hole counts as 0): false when the box is not all loaded.
  bool vs_bounds(Coord lo, Coord hi, float* vs_lo, float* vs_hi) const;

  const ModelValues& values(int32_t i) const { return values_[i]; }
  Octant octant(int32_t i) const { return octant_from_key(keys_[i]); }
  size_t octants() const { return keys_.size(); }
  int shift() const { return shift_; }

 private:
  int32_t search(Coord p) const;
  // The octant holding pixel p of raster cell c, or kHole.
  int32_t find_in_cell(size_t c, Coord p) const {
    const int32_t v = raster_[c];
    return v != kMixed ? v : search(p);
  }
  float octant_vs(int32_t i) const { return i == kHole ? 0.0f : values_[i][1]; }
  // Each point's cell index (i, j, k as in Lattice) from its axes' parts.
  template <class Answer>
  void each_cell(const Lattice& l, const Answer& answer) const;
  // The cursor over the table, kept from load to load (the table is read
  // only while regions load from it): a cell whose records lie in the leaf
  // it holds is found there.
  struct Scan {
    const BTree* table = nullptr;
    BTreeCursor cursor;
    bool known = false;  // the cursor stands on the first record at or after k0
    uint64_t k0 = 0;
    // Positions the cursor on the first record at or after k.
    Status seek(BTree& t, uint64_t k);
    // The record with the greatest key at or below k, after seek(k).
    Status floor(BTree& t, uint64_t k, uint64_t* key, std::byte* record, size_t record_bytes,
                 bool* found);
  };
  Status scan_cell(BTree& table, const Octant& cell, size_t record_bytes, size_t max_octants,
                   bool* full);
  void add_run(const uint64_t* keys, const std::byte* records, size_t n, size_t record_bytes);
  bool add_meeting(const uint64_t* keys, const std::byte* records, size_t n, size_t record_bytes,
                   size_t room);
  void build_raster();
  // Writes the loaded octants into the raster and their cells' Vs ranges;
  // the cells written.
  size_t fill_cells();
  size_t fill_octant_cells(size_t i, size_t* mixed_cell);
  // The cells' Vs bounds (pyramid level 0) and the levels above them.
  void build_bounds();
  // The Vs bounds of cell (x, y, z) of pyramid level p.
  struct VsRange {
    float lo, hi;
  };
  const VsRange& range(int p, uint32_t x, uint32_t y, uint32_t z) const {
    const Level& l = pyramid_[p];
    return l.ranges[(size_t{z} * l.dims[1] + y) * l.dims[0] + x];
  }

  bool loaded_ = false;
  Coord lo_{0, 0, 0}, hi_{0, 0, 0};
  std::vector<uint64_t> keys_;  // sorted, disjoint octants
  std::vector<ModelValues> values_;
  uint32_t split_edge_ = 1;  // cells larger than this reaching past the box are read as children
  int finest_ = 0;           // the finest octant's level
  int shift_ = 0;
  uint64_t max_cells_ = kMinCells;
  DecodedLeaves* decoded_ = nullptr;
  uint32_t base_[3] = {0, 0, 0};  // lo >> shift_
  uint32_t dims_[3] = {0, 0, 0};
  std::vector<int32_t> raster_;
  Scan scan_;
  struct Level {
    uint32_t dims[3];
    std::vector<VsRange> ranges;
  };
  std::vector<Level> pyramid_;  // [0]: the raster's cells; each next halves every side
  size_t levels_ = 0;           // the pyramid's levels in use (the rest keep their memory)
};

}  // namespace weaver
