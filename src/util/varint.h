// LEB128 varints: unsigned integers in 7-bit groups, low first, the high bit
// of each byte set when another follows (the wire form of the octant keys
// weaver-mpi's ranks exchange: util/octant_key_stream.h).
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

}  // namespace weaver
