#include "modeldb/model_region.h"

#include <algorithm>
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

void ModelRegion::clear() {
  loaded_ = false;
  keys_.clear();
  values_.clear();
  raster_.clear();
}

Status ModelRegion::load(BTree& table, Coord lo, Coord hi, size_t record_bytes,
                         size_t max_octants) {
  clear();
  lo_ = lo;
  hi_ = hi;
  bool full = false;
  for (const Octant& cell : covering_cells(lo, hi)) {
    WEAVER_RETURN_IF_ERROR(scan_cell(table, cell, record_bytes, max_octants, &full));
    if (full) {
      clear();
      return Status::Ok();
    }
  }
  build_raster();
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
  WEAVER_RETURN_IF_ERROR(floor_holding(table, cell, &floor_key, record, &found));
  if (found) {
    // Cells inside one octant come one after another in Z-order.
    if (keys_.empty() || keys_.back() != floor_key) add(floor_key, record, record_bytes);
    return Status::Ok();
  }
  const uint64_t end = octant_key_subtree_end(cell);
  // A cell reaches past the box by up to its own size: its octants there
  // are skipped, not kept (about half of what the scans read).
  const bool inside = octant_in_box(cell, lo_, hi_);
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(table.seek_cursor(octant_key(cell), &c));
  while (c.valid() && c.key() < end) {
    if (keys_.size() == max_octants) {
      *full = true;
      return Status::Ok();
    }
    if (inside || octant_meets_box(octant_from_key(c.key()), lo_, hi_)) {
      add(c.key(), c.payload(), record_bytes);
    }
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  return Status::Ok();
}

void ModelRegion::add(uint64_t key, const std::byte* record, size_t record_bytes) {
  keys_.push_back(key);
  ModelValues v{};
  std::memcpy(v.data(), record, std::min(record_bytes, sizeof v));
  values_.push_back(v);
}

void ModelRegion::build_raster() {
  int finest = 0;
  for (uint64_t k : keys_) finest = std::max(finest, octant_key_level(k));
  shift_ = kMaxLevel - finest;
  const uint32_t lo[3] = {lo_.x, lo_.y, lo_.z}, hi[3] = {hi_.x, hi_.y, hi_.z};
  for (;; ++shift_) {
    for (int a = 0; a < 3; ++a) {
      base_[a] = lo[a] >> shift_;
      dims_[a] = (hi[a] >> shift_) - base_[a] + 1;
    }
    if (uint64_t{dims_[0]} * dims_[1] * dims_[2] <= kMaxCells) break;
  }
  raster_.assign(size_t{dims_[0]} * dims_[1] * dims_[2], kHole);
  for (size_t i = 0; i < keys_.size(); ++i) {
    const Octant o = octant_from_key(keys_[i]);
    const uint32_t corner[3] = {o.x, o.y, o.z};
    const uint32_t last = octant_edge(o) - 1;
    const bool whole_cells = o.level <= kMaxLevel - shift_;
    uint32_t from[3], to[3];
    bool meets = true;
    for (int a = 0; a < 3; ++a) {
      const int64_t f = int64_t(corner[a] >> shift_) - base_[a];
      const int64_t t = int64_t((corner[a] + last) >> shift_) - base_[a];
      from[a] = static_cast<uint32_t>(std::max<int64_t>(f, 0));
      to[a] = static_cast<uint32_t>(std::min<int64_t>(t, dims_[a] - 1));
      meets = meets && t >= 0 && f < dims_[a];
    }
    if (!meets) continue;
    const int32_t v = whole_cells ? static_cast<int32_t>(i) : kMixed;
    for (uint32_t z = from[2]; z <= to[2]; ++z)
      for (uint32_t y = from[1]; y <= to[1]; ++y)
        for (uint32_t x = from[0]; x <= to[0]; ++x) {
          raster_[(size_t{z} * dims_[1] + y) * dims_[0] + x] = v;
        }
  }
}

int32_t ModelRegion::search(Coord p) const {
  const auto it = std::upper_bound(keys_.begin(), keys_.end(), pixel_key(p));
  if (it == keys_.begin()) return kHole;
  const int32_t i = static_cast<int32_t>(it - keys_.begin() - 1);
  return octant_contains_point(octant_from_key(keys_[i]), p) ? i : kHole;
}

}  // namespace weaver
