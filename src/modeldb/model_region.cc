#include "modeldb/model_region.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "db/octant_table.h"
#include "storage/btree.h"
#include "storage/btree_cursor.h"

namespace weaver {
namespace {

// The aligned cells, of at least a quarter of the box's largest side, that
// cover the box, in Z-order: at most 5 a side, and about twice the box's
// volume on average, so a scan reads little outside the box.
std::vector<Octant> covering_cells(Coord lo, Coord hi) {
  const uint32_t side = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) + 1;
  int level = kMaxLevel;
  while (level > 0 && uint64_t{octant_edge(level)} * 4 < side) --level;
  const int s = kMaxLevel - level;
  std::vector<Octant> cells;
  for (uint32_t z = lo.z >> s; z <= hi.z >> s; ++z)
    for (uint32_t y = lo.y >> s; y <= hi.y >> s; ++y)
      for (uint32_t x = lo.x >> s; x <= hi.x >> s; ++x) {
        cells.push_back({x << s, y << s, z << s, static_cast<uint8_t>(level)});
      }
  std::sort(cells.begin(), cells.end(),
            [](const Octant& a, const Octant& b) { return octant_key(a) < octant_key(b); });
  return cells;
}

}  // namespace

// The raster keeps its cells (unread while nothing is loaded): a load that
// writes every cell need not fill them first (build_raster).
void ModelRegion::clear() {
  loaded_ = false;
  keys_.clear();
  values_.clear();
}

Status ModelRegion::load(BTree& table, Coord lo, Coord hi, size_t record_bytes,
                         size_t max_octants) {
  clear();
  lo_ = lo;
  hi_ = hi;
  bool full = false;
  // One cursor for all the cells and loads: a cell whose records lie in the
  // leaf it holds is found there (a seek from the tree decodes a whole
  // packed leaf again: 60% of a construct from a model database whose
  // subtrees are small).
  if (scan_.table != &table) {
    scan_ = Scan();
    scan_.table = &table;
    scan_.cursor.keep_decoded(decoded_);
  }
  // Room for the most octants a region holds, made once: the vectors never
  // grow (and so never hold twice what they use while they copy).
  keys_.reserve(max_octants);
  values_.reserve(max_octants);
  const uint32_t side = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}) + 1;
  split_edge_ = 1;
  while (uint64_t{split_edge_} * 16 < side) split_edge_ *= 2;
  for (const Octant& cell : covering_cells(lo, hi)) {
    WEAVER_RETURN_IF_ERROR(scan_cell(table, cell, record_bytes, max_octants, &full));
    if (full) {
      clear();
      return Status::Ok();
    }
  }
  build_raster();
  build_bounds();
  loaded_ = true;
  return Status::Ok();
}

// The octants of one cell: the one model octant holding all of it (the
// floor of its key), or those inside it, by a scan of its subtree.
Status ModelRegion::scan_cell(BTree& table, const Octant& cell, size_t record_bytes,
                              size_t max_octants, bool* full) {
  std::byte record[sizeof(ModelValues)] = {};
  uint64_t floor_key = 0;
  bool found = false;
  WEAVER_RETURN_IF_ERROR(scan_.seek(table, octant_key(cell)));
  WEAVER_RETURN_IF_ERROR(
      scan_.floor(table, octant_key(cell), &floor_key, record, record_bytes, &found));
  found = found && key_holds(floor_key, cell);
  if (found) {
    // Cells inside one octant come one after another in Z-order.
    if (keys_.empty() || keys_.back() != floor_key) {
      if (keys_.size() == max_octants) {
        *full = true;
        return Status::Ok();
      }
      add_run(&floor_key, record, 1, record_bytes);
    }
    return Status::Ok();
  }
  const bool inside = octant_in_box(cell, lo_, hi_);
  if (!inside && octant_edge(cell) > split_edge_) {
    // A cell reaching past the box is read as its children that meet it,
    // down to cells of a sixteenth of the box: the records outside were
    // half of those read, each tested against the box.
    for (int k = 0; k < 8; ++k) {
      const Octant child = octant_child(cell, k);
      if (!octant_meets_box(child, lo_, hi_)) continue;
      WEAVER_RETURN_IF_ERROR(scan_cell(table, child, record_bytes, max_octants, full));
      if (*full) return Status::Ok();
    }
    return Status::Ok();
  }
  const uint64_t end = octant_key_subtree_end(cell);
  // The smallest cells reach past the box by up to their own size: their
  // octants there are skipped, not kept.
  BTreeCursor& c = scan_.cursor;
  // The cursor moves past k0: it will stand on the first record at or
  // after the cell's end (a later load may ask for a key before that).
  scan_.known = false;
  // A leaf's run of the cell's records at a time: inside the box all are
  // kept, else those meeting it.
  while (c.valid() && c.key() < end) {
    uint32_t n = 0;
    const uint64_t* keys = c.keys_in_leaf(&n);
    const uint32_t in_cell = static_cast<uint32_t>(std::lower_bound(keys, keys + n, end) - keys);
    const size_t room = max_octants - keys_.size();
    if (inside ? in_cell > room : !add_meeting(keys, c.payload(), in_cell, record_bytes, room)) {
      *full = true;
      return Status::Ok();
    }
    if (inside) add_run(keys, c.payload(), in_cell, record_bytes);
    WEAVER_RETURN_IF_ERROR(c.skip(in_cell));
  }
  scan_.known = true, scan_.k0 = end;
  return Status::Ok();
}

// When the cursor stands on the first record at or after k0 <= k and that
// record is at k or later (or there is none), it is the first at or after k
// too; when k lies within the leaf it holds, the leaf's decoded keys find
// it; else the tree does.
Status ModelRegion::Scan::seek(BTree& t, uint64_t k) {
  const bool stays = known && k0 <= k && (!cursor.valid() || cursor.key() >= k);
  if (!stays && !cursor.seek_in_leaf(k)) {
    known = false;
    WEAVER_RETURN_IF_ERROR(t.seek_cursor(k, &cursor));
  }
  known = true, k0 = k;
  return Status::Ok();
}

// The cursor stands on the first record at or after k: that record if it
// is k's, else the one before it in its leaf; the tree answers when that
// is in another leaf.
Status ModelRegion::Scan::floor(BTree& t, uint64_t k, uint64_t* key, std::byte* record,
                                size_t record_bytes, bool* found) {
  const std::byte* payload = nullptr;
  if (cursor.valid() && cursor.key() == k) {
    *key = k, payload = cursor.payload();
  } else if (!cursor.before_in_leaf(key, &payload)) {
    return t.floor(k, key, record, found);
  }
  std::memcpy(record, payload, std::min(record_bytes, sizeof(ModelValues)));
  *found = true;
  return Status::Ok();
}

namespace {

// Record i's fields (its first min(record_bytes, 20) bytes) into out, which
// holds zeros past them.  A copy of a size known when compiled for the
// model tables' two record sizes (vp, vs, rho; and with qp, qs), not a
// call to memcpy a record (a 0.5 Hz construct from the 100 m model
// database: 0.958x the instructions).
void copy_record(const std::byte* records, size_t i, size_t record_bytes, ModelValues& out) {
  const std::byte* r = records + i * record_bytes;
  if (record_bytes == 12) {
    std::memcpy(out.data(), r, 12);
  } else if (record_bytes == sizeof(ModelValues)) {
    std::memcpy(out.data(), r, sizeof(ModelValues));
  } else {
    std::memcpy(out.data(), r, std::min(record_bytes, sizeof(ModelValues)));
  }
}

}  // namespace

// n records in a row (keys, and their records record_bytes apart).
void ModelRegion::add_run(const uint64_t* keys, const std::byte* records, size_t n,
                          size_t record_bytes) {
  keys_.insert(keys_.end(), keys, keys + n);
  const size_t at = values_.size();
  values_.resize(at + n);
  for (size_t i = 0; i < n; ++i) copy_record(records, i, record_bytes, values_[at + i]);
}

// Of n records in a row, those meeting the box; false if they number more
// than room.
bool ModelRegion::add_meeting(const uint64_t* keys, const std::byte* records, size_t n,
                              size_t record_bytes, size_t room) {
  const size_t most = keys_.size() + room;
  for (size_t i = 0; i < n; ++i) {
    if (!octant_meets_box(octant_from_key(keys[i]), lo_, hi_)) continue;
    if (keys_.size() == most) return false;
    keys_.push_back(keys[i]);
    copy_record(records, i, record_bytes, values_.emplace_back());
  }
  return true;
}

void ModelRegion::build_raster() {
  finest_ = 0;
  for (uint64_t k : keys_) finest_ = std::max(finest_, octant_key_level(k));
  shift_ = kMaxLevel - finest_;
  const uint32_t lo[3] = {lo_.x, lo_.y, lo_.z}, hi[3] = {hi_.x, hi_.y, hi_.z};
  for (;; ++shift_) {
    for (int a = 0; a < 3; ++a) {
      base_[a] = lo[a] >> shift_;
      dims_[a] = (hi[a] >> shift_) - base_[a] + 1;
    }
    if (uint64_t{dims_[0]} * dims_[1] * dims_[2] <= max_cells_) break;
  }
  const size_t cells = size_t{dims_[0]} * dims_[1] * dims_[2];
  if (pyramid_.empty()) pyramid_.emplace_back();
  Level& base = pyramid_[0];
  std::copy(dims_, dims_ + 3, base.dims);
  // The octants of most loads cover every cell of the box (a model has no
  // holes, and the box lies inside it): the cells are written as they are,
  // without marking them holes first (that fill was a twentieth of a
  // load), and only where some cell was left are they filled and written
  // again.
  raster_.resize(cells);
  base.ranges.resize(cells);
  if (fill_cells() != cells) {
    raster_.assign(cells, kHole);
    base.ranges.assign(cells, VsRange{0.0f, 0.0f});
    fill_cells();
  }
}

// The cells' Vs ranges (the pyramid's level 0) as the raster is filled,
// octant by octant: a pass over the cells after it read each octant's
// values in the raster's order, a cache miss a cell.  A hole is Vs 0; a
// mixed cell's range is found in build_bounds.  The octants are disjoint,
// and those of a mixed cell come one after another (a cell is an aligned
// block of the key order), so each cell counted is counted once.
size_t ModelRegion::fill_cells() {
  // The members the loop reads, as locals: the stores to the cells could
  // alias them otherwise, and each octant would load them again.
  const int shift = shift_, cell_level = kMaxLevel - shift;
  const uint32_t base[3] = {base_[0], base_[1], base_[2]};
  const uint32_t dims[3] = {dims_[0], dims_[1], dims_[2]};
  const uint64_t* keys = keys_.data();
  const ModelValues* values = values_.data();
  int32_t* raster = raster_.data();
  VsRange* ranges = pyramid_[0].ranges.data();
  const size_t n = keys_.size();
  size_t written = 0, mixed_cell = SIZE_MAX;
  for (size_t i = 0; i < n; ++i) {
    if (octant_key_level(keys[i]) != cell_level) {
      written += fill_octant_cells(i, &mixed_cell);
      continue;
    }
    // One cell exactly (most octants: the raster's cells are the finest
    // octants' size wherever the box affords it).  A cell before the
    // box's wraps round to a large index and is skipped.
    const Coord p = morton_decode(octant_key_morton(keys[i]));
    const uint32_t x = (p.x >> shift) - base[0], y = (p.y >> shift) - base[1],
                   z = (p.z >> shift) - base[2];
    if (x >= dims[0] || y >= dims[1] || z >= dims[2]) continue;
    const size_t c = (size_t{z} * dims[1] + y) * dims[0] + x;
    const float vs = values[i][1];
    raster[c] = static_cast<int32_t>(i);
    ranges[c] = VsRange{vs, vs};
    ++written;
  }
  return written;
}

// Octant i, larger or smaller than a cell, into the cells it meets: the
// cells written (a mixed cell once: *mixed_cell is the last one counted).
size_t ModelRegion::fill_octant_cells(size_t i, size_t* mixed_cell) {
  const Octant o = octant_from_key(keys_[i]);
  const int cell_level = kMaxLevel - shift_;
  const uint32_t corner[3] = {o.x, o.y, o.z};
  const uint32_t last = octant_edge(o) - 1;
  const bool whole_cells = o.level <= cell_level;
  uint32_t from[3], to[3];
  for (int a = 0; a < 3; ++a) {
    const int64_t f = int64_t(corner[a] >> shift_) - base_[a];
    const int64_t t = int64_t((corner[a] + last) >> shift_) - base_[a];
    if (t < 0 || f >= dims_[a]) return 0;
    from[a] = static_cast<uint32_t>(std::max<int64_t>(f, 0));
    to[a] = static_cast<uint32_t>(std::min<int64_t>(t, dims_[a] - 1));
  }
  const int32_t v = whole_cells ? static_cast<int32_t>(i) : kMixed;
  const float vs = values_[i][1];
  const VsRange range = whole_cells ? VsRange{vs, vs} : VsRange{HUGE_VALF, -HUGE_VALF};
  const size_t row = to[0] - from[0] + 1;
  size_t written = 0;
  for (uint32_t z = from[2]; z <= to[2]; ++z)
    for (uint32_t y = from[1]; y <= to[1]; ++y) {
      const size_t c = (size_t{z} * dims_[1] + y) * dims_[0] + from[0];
      std::fill_n(raster_.data() + c, row, v);
      std::fill_n(pyramid_[0].ranges.data() + c, row, range);
      if (whole_cells) {
        written += row;
      } else if (c != *mixed_cell) {
        *mixed_cell = c;
        ++written;
      }
    }
  return written;
}

void ModelRegion::build_bounds() {
  Level& base = pyramid_[0];  // its cells' ranges: build_raster's
  // Mixed cells: the least and greatest Vs of the octants inside, and how
  // much of the cell's part in the box they fill (less: a hole, Vs 0).  A
  // cell is an aligned block of the key order, so its octants come one
  // after another: each cell's count is finished when the next begins (no
  // count per cell of the raster, no pass over them all).
  const uint32_t box_lo[3] = {lo_.x, lo_.y, lo_.z}, box_hi[3] = {hi_.x, hi_.y, hi_.z};
  // The pixels of [from, from + edge) on each axis inside the box.
  const auto in_box = [&](const uint32_t from[3], uint32_t edge) {
    uint64_t n = 1;
    for (int a = 0; a < 3; ++a) {
      const uint64_t f = std::max(from[a], box_lo[a]);
      const uint64_t t = std::min<uint64_t>(uint64_t{from[a]} + edge - 1, box_hi[a]);
      n *= t >= f ? t - f + 1 : 0;
    }
    return n;
  };
  size_t cell = SIZE_MAX;  // the mixed cell whose octants are being counted
  uint32_t cell_corner[3] = {0, 0, 0};
  uint64_t filled = 0;
  const auto finish_cell = [&] {
    if (cell == SIZE_MAX || filled >= in_box(cell_corner, uint32_t{1} << shift_)) return;
    base.ranges[cell].lo = std::min(base.ranges[cell].lo, 0.0f);
    base.ranges[cell].hi = std::max(base.ranges[cell].hi, 0.0f);
  };
  // No octant finer than a cell (the raster's cells are the finest
  // octant's size): no mixed cells.
  const size_t mixed_octants = kMaxLevel - shift_ < finest_ ? keys_.size() : 0;
  for (size_t i = 0; i < mixed_octants; ++i) {
    const Octant o = octant_from_key(keys_[i]);
    if (o.level <= kMaxLevel - shift_) continue;  // whole cells: ranged in build_raster
    const uint32_t cx = (o.x >> shift_) - base_[0], cy = (o.y >> shift_) - base_[1],
                   cz = (o.z >> shift_) - base_[2];
    if (cx >= dims_[0] || cy >= dims_[1] || cz >= dims_[2]) continue;  // outside the box
    const size_t c = cell_index(cx, cy, cz);
    if (c != cell) {
      finish_cell();
      cell = c, filled = 0;
      cell_corner[0] = (cx + base_[0]) << shift_;
      cell_corner[1] = (cy + base_[1]) << shift_;
      cell_corner[2] = (cz + base_[2]) << shift_;
    }
    const uint32_t corner[3] = {o.x, o.y, o.z};
    filled += in_box(corner, octant_edge(o));
    VsRange& r = base.ranges[c];
    r.lo = std::min(r.lo, values_[i][1]);
    r.hi = std::max(r.hi, values_[i][1]);
  }
  finish_cell();
  // The levels above, in the vectors of the last load's (a level made
  // afresh at every load was memory faulted in afresh).
  levels_ = 1;
  while (pyramid_[levels_ - 1].dims[0] > 1 || pyramid_[levels_ - 1].dims[1] > 1 ||
         pyramid_[levels_ - 1].dims[2] > 1) {
    if (pyramid_.size() == levels_) pyramid_.emplace_back();
    const Level& fine = pyramid_[levels_ - 1];
    Level& up = pyramid_[levels_];
    for (int a = 0; a < 3; ++a) up.dims[a] = (fine.dims[a] + 1) / 2;
    up.ranges.assign(size_t{up.dims[0]} * up.dims[1] * up.dims[2], VsRange{HUGE_VALF, -HUGE_VALF});
    for (uint32_t z = 0; z < fine.dims[2]; ++z)
      for (uint32_t y = 0; y < fine.dims[1]; ++y) {
        const VsRange* f = &fine.ranges[(size_t{z} * fine.dims[1] + y) * fine.dims[0]];
        VsRange* u = &up.ranges[(size_t{z / 2} * up.dims[1] + y / 2) * up.dims[0]];
        // Two fine cells an up cell: one update of it, not two.
        uint32_t x = 0;
        for (; x + 1 < fine.dims[0]; x += 2) {
          VsRange& t = u[x / 2];
          t.lo = std::min(t.lo, std::min(f[x].lo, f[x + 1].lo));
          t.hi = std::max(t.hi, std::max(f[x].hi, f[x + 1].hi));
        }
        if (x < fine.dims[0]) {
          u[x / 2].lo = std::min(u[x / 2].lo, f[x].lo);
          u[x / 2].hi = std::max(u[x / 2].hi, f[x].hi);
        }
      }
    ++levels_;
  }
}

bool ModelRegion::vs_bounds(Coord lo, Coord hi, float* vs_lo, float* vs_hi) const {
  if (!covers(lo) || !covers(hi)) return false;
  const uint32_t from[3] = {cell_x(lo.x), cell_y(lo.y), cell_z(lo.z)};
  const uint32_t to[3] = {cell_x(hi.x), cell_y(hi.y), cell_z(hi.z)};
  int p = 0;
  while (p + 1 < int(levels_) &&
         ((to[0] >> p) - (from[0] >> p) > 2 || (to[1] >> p) - (from[1] >> p) > 2 ||
          (to[2] >> p) - (from[2] >> p) > 2)) {
    ++p;
  }
  float l = HUGE_VALF, h = -HUGE_VALF;
  for (uint32_t z = from[2] >> p; z <= to[2] >> p; ++z)
    for (uint32_t y = from[1] >> p; y <= to[1] >> p; ++y)
      for (uint32_t x = from[0] >> p; x <= to[0] >> p; ++x) {
        const VsRange& r = range(p, x, y, z);
        l = std::min(l, r.lo);
        h = std::max(h, r.hi);
      }
  *vs_lo = l, *vs_hi = h;
  return true;
}

// The cell index split by axis: x's part, y's times a row, z's times a
// plane, added for each point (a multiply-add a point, and the raster's
// members kept in registers, where vs_at reloaded them for every store).
template <class Answer>
void ModelRegion::each_cell(const Lattice& l, const Answer& answer) const {
  const int n = l.n;
  size_t part_y[kLatticeMost], part_z[kLatticeMost];
  const size_t row = dims_[0], plane = size_t{dims_[0]} * dims_[1];
  for (int i = 0; i < n; ++i) part_y[i] = l.c[1][i] * row, part_z[i] = l.c[2][i] * plane;
  const uint32_t* cx = l.c[0];
  int index = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j) {
      const size_t base = part_z[k] + part_y[j];
      for (int i = 0; i < n; ++i, ++index) answer(index, base + cx[i], i, j, k);
    }
}

void ModelRegion::vs_on_lattice(const Lattice& l, float* out) const {
  const VsRange* ranges = pyramid_[0].ranges.data();
  each_cell(l, [&](int index, size_t c, int i, int j, int k) {
    const VsRange r = ranges[c];
    out[index] =
        r.lo == r.hi ? r.lo : octant_vs(find_in_cell(c, {l.p[0][i], l.p[1][j], l.p[2][k]}));
  });
}

void ModelRegion::find_on_lattice(const Lattice& l, int32_t* out) const {
  each_cell(l, [&](int index, size_t c, int i, int j, int k) {
    out[index] = find_in_cell(c, {l.p[0][i], l.p[1][j], l.p[2][k]});
  });
}

int32_t ModelRegion::search(Coord p) const {
  const auto it = std::upper_bound(keys_.begin(), keys_.end(), pixel_key(p));
  if (it == keys_.begin()) return kHole;
  const int32_t i = static_cast<int32_t>(it - keys_.begin() - 1);
  return octant_contains_point(octant_from_key(keys_[i]), p) ? i : kHole;
}

}  // namespace weaver
