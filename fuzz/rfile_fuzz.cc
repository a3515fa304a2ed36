// SW4 rfile headers (model/rfile.h) and ESRI ASCII rasters (model/surface.h):
// the first byte picks the parser, the rest is the file.
#include <cmath>
#include <string>

#include "model/rfile.h"
#include "model/surface.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const unsigned char* p = data + 1;
  const size_t n = size - 1;
  if (data[0] & 1) {
    weaver::AscRaster r;
    if (weaver::parse_asc(std::string(reinterpret_cast<const char*>(p), n), "fuzz", 1 << 16, &r)
            .ok()) {
      // An accepted raster holds every cell it promised, each a number or NODATA.
      if (r.z.size() != size_t(r.ncols) * r.nrows || !(r.dx > 0) || !(r.dy > 0)) __builtin_trap();
      for (float v : r.z) {
        if (!std::isnan(v) && !(std::abs(v) <= 1e5)) __builtin_trap();
      }
    }
    return 0;
  }
  weaver::RfileHeader h;
  if (weaver::parse_rfile_header(p, n, n, "fuzz", &h).ok()) {
    // An accepted header's blocks fill the file exactly, in order.
    uint64_t at = h.blocks[0].offset;
    for (const weaver::RfileBlock& b : h.blocks) {
      if (b.offset != at || b.ni < 2 || b.nj < 2 || !(b.hh > 0)) __builtin_trap();
      at += b.values() * uint64_t(h.precision);
    }
    if (at != n || h.blocks.size() < 2) __builtin_trap();
  }
  return 0;
}
