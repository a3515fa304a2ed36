#include "balance/domain_map.h"

#include <algorithm>

#include "schema/octant.h"

namespace weaver {
namespace {

// Sets bits [begin, begin + count) of `bits`.
void set_bits(std::vector<uint64_t>& bits, uint64_t begin, uint64_t count) {
  const uint64_t end = begin + count;
  for (; begin < end && begin % 64 != 0; ++begin) bits[begin / 64] |= uint64_t{1} << (begin % 64);
  for (; begin + 64 <= end; begin += 64) bits[begin / 64] = ~uint64_t{0};
  for (; begin < end; ++begin) bits[begin / 64] |= uint64_t{1} << (begin % 64);
}

bool any_bit(const std::vector<uint64_t>& bits, uint64_t begin, uint64_t count) {
  const uint64_t end = begin + count;
  for (; begin < end && begin % 64 != 0; ++begin) {
    if (bits[begin / 64] >> (begin % 64) & 1) return true;
  }
  for (; begin + 64 <= end; begin += 64) {
    if (bits[begin / 64] != 0) return true;
  }
  for (; begin < end; ++begin) {
    if (bits[begin / 64] >> (begin % 64) & 1) return true;
  }
  return false;
}

bool all_bits(const std::vector<uint64_t>& bits, uint64_t begin, uint64_t count) {
  for (uint64_t i = begin; i < begin + count; ++i) {
    if (!(bits[i / 64] >> (i % 64) & 1)) return false;
  }
  return true;
}

bool bit(const std::vector<uint64_t>& bits, uint64_t i) { return bits[i / 64] >> (i % 64) & 1; }

// Cells of level `level` are Morton codes with 3 * (20 - level) low bits dropped.
int cell_shift(int level) { return 3 * (kMaxLevel - level); }

}  // namespace

int DomainMap::level_for(uint64_t bytes, int finest_leaf_level) {
  int level = 0;
  // Two bit vectors of 8^L bits: 8^L / 4 bytes.
  while (level < std::min(finest_leaf_level, kMaxLevel) &&
         (uint64_t{1} << (3 * (level + 1))) / 4 <= bytes) {
    ++level;
  }
  return level;
}

DomainMap::DomainMap(int level) : level_(level) {
  const uint64_t words = std::max<uint64_t>(1, (uint64_t{1} << (3 * level)) / 64);
  any_.assign(words, 0);
  full_.assign(words, 0);
}

void DomainMap::Writer::add_leaf(uint64_t key) {
  const int level = map_->level_;
  const int l = octant_key_level(key);
  const uint64_t m = octant_key_morton(key);
  if (l <= level) {  // covers whole cells
    close_cell();
    const uint64_t count = uint64_t{1} << (3 * (level - l));
    set_bits(map_->any_, m >> cell_shift(level), count);
    set_bits(map_->full_, m >> cell_shift(level), count);
    return;
  }
  const uint64_t cell = m >> cell_shift(level);
  if (!open_ || cell != cell_) {
    close_cell();
    cell_ = cell;
    open_ = true;
  }
  volume_ += uint64_t{1} << cell_shift(l);
}

void DomainMap::Writer::close_cell() {
  if (!open_) return;
  set_bits(map_->any_, cell_, 1);
  // Leaves do not overlap, so their volumes add up to the cell's only
  // when they cover it.
  if (volume_ == uint64_t{1} << cell_shift(map_->level_)) set_bits(map_->full_, cell_, 1);
  open_ = false;
  volume_ = 0;
}

// A stretch's leaves write the bits of their own cells, which lie in its
// words, and a coarse leaf's whole cells: a run of 8^k cells aligned to
// its length, so either within one word or whole words that no other
// leaf's cells share.
uint64_t DomainMap::stretch_start(uint64_t key) const {
  const uint64_t cell = (octant_key_morton(key) >> cell_shift(level_)) & ~uint64_t{63};
  return ((cell << cell_shift(level_)) >> 3) << 7;  // the first key at that corner
}

DomainMap::Answer DomainMap::overlaps(uint64_t key) const {
  const int l = octant_key_level(key);
  const uint64_t first = octant_key_morton(key) >> cell_shift(level_);
  if (l < level_) {  // whole cells: overlaps iff some leaf overlaps one of them
    return any_bit(any_, first, uint64_t{1} << (3 * (level_ - l))) ? Answer::kYes : Answer::kNo;
  }
  if (!bit(any_, first)) return Answer::kNo;
  if (bit(full_, first)) return Answer::kYes;
  return Answer::kAskTheLeaves;
}

bool DomainMap::covers(uint64_t key) const {
  const int l = octant_key_level(key);
  const uint64_t first = octant_key_morton(key) >> cell_shift(level_);
  if (l >= level_) return bit(full_, first);
  // Up to 512 cells are read; a coarser octant is left to the leaves.
  if (level_ - l > 3) return false;
  return all_bits(full_, first, uint64_t{1} << (3 * (level_ - l)));
}

}  // namespace weaver
