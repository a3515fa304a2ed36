// Increasing 64-bit keys as LEB128 varints of their differences: the wire
// form of the keys weaver-mpi's ranks exchange (a rank's corners and
// insulation octants are sorted and close together, so 2 or 3 bytes each
// instead of 8).
#pragma once

#include <cstdint>
#include <string>

namespace weaver {

inline void append_varint(std::string& out, uint64_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<char>(v | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<char>(v));
}

// Reads a varint at *pos (advancing it); false past the end or on a varint
// longer than 10 bytes.
inline bool read_varint(const std::string& in, size_t* pos, uint64_t* v) {
  *v = 0;
  for (int shift = 0; shift < 70 && *pos < in.size(); shift += 7) {
    const uint8_t b = static_cast<uint8_t>(in[(*pos)++]);
    *v |= uint64_t{b & 0x7fu} << shift;
    if (b < 0x80) return true;
  }
  return false;
}

// A key after `last` (the first after 0): its difference.
inline void append_key_delta(std::string& out, uint64_t* last, uint64_t key) {
  append_varint(out, key - *last);
  *last = key;
}
inline bool read_key_delta(const std::string& in, size_t* pos, uint64_t* last, uint64_t* key) {
  uint64_t d = 0;
  if (!read_varint(in, pos, &d)) return false;
  *key = *last += d;
  return true;
}

}  // namespace weaver
