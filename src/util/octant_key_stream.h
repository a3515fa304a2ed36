// Increasing octant keys on the wire between weaver-mpi's ranks (ghost
// layers, insulation layers).  Each key is one varint: how many octants of
// its own size its Morton code lies past the last key's (rounded down to
// that size), times 32, plus its level.  Leaves along a surface are a few
// octants of their size apart, so one or two bytes each, where the plain
// difference of keys (util/varint.h) takes five or six at level 10.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "schema/octant.h"
#include "util/varint.h"

namespace weaver {

// *last_morton starts at 0 and follows the keys.
// REQUIRES: key valid and after the last one.
inline void append_octant_key(std::string& out, uint64_t* last_morton, uint64_t key) {
  const int level = octant_key_level(key), shift = 3 * (kMaxLevel - level);
  const uint64_t m = octant_key_morton(key);
  append_varint(out, ((m >> shift) - (*last_morton >> shift)) << 5 | static_cast<uint64_t>(level));
  *last_morton = m;
}

// False past the end, or on a level or code out of range (bytes that
// append_octant_key did not write).
inline bool read_octant_key(const std::string& in, size_t* pos, uint64_t* last_morton,
                            uint64_t* key) {
  uint64_t v = 0;
  if (!read_varint(in, pos, &v) || (v & 31) > kMaxLevel) return false;
  const int level = static_cast<int>(v & 31), shift = 3 * (kMaxLevel - level);
  const uint64_t cells = (*last_morton >> shift) + (v >> 5), limit = uint64_t{1} << (3 * level);
  if ((v >> 5) >= limit || cells >= limit) return false;
  const uint64_t m = cells << shift;
  *key = ((m >> 3) << 7) | (level < kMaxLevel ? uint64_t(level) : kKeyLevel20Slot + (m & 7));
  *last_morton = m;
  return true;
}

// A whole sorted list of keys, and back (appended to *out; false on bytes
// cut short or damaged).
inline std::string encode_octant_keys(const std::vector<uint64_t>& keys) {
  std::string out;
  uint64_t last = 0;
  for (uint64_t k : keys) append_octant_key(out, &last, k);
  return out;
}
inline bool decode_octant_keys(const std::string& bytes, std::vector<uint64_t>* out) {
  size_t pos = 0;
  uint64_t last = 0, key = 0;
  while (pos < bytes.size()) {
    if (!read_octant_key(bytes, &pos, &last, &key)) return false;
    out->push_back(key);
  }
  return true;
}

}  // namespace weaver
