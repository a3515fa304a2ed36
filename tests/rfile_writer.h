// The test's own SW4 rfile writer (the layout of model/rfile.h, written
// independently of weaver's reader).
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace weaver {

struct Block {
  double hh, hv, z0;
  int nc, ni, nj, nk;
  std::function<std::vector<double>(int, int, int)> value;  // nc values at (i, j, k)
};

// The rfile layout, written independently of the reader.
class RfileWriter {
 public:
  bool big_endian = false;
  int precision = 4;
  int attenuation = -1;  // -1: from the blocks
  std::string proj = "+proj=utm +zone=11";

  std::string bytes(const std::vector<Block>& blocks) {
    out_.clear();
    i32(1);
    i32(precision);
    i32(attenuation >= 0 ? attenuation : blocks[1].nc == 5);
    f64(12.5), f64(-118.25), f64(34.5);
    i32(int(proj.size()));
    out_ += proj;
    i32(int(blocks.size()));
    for (const Block& b : blocks) {
      f64(b.hh), f64(b.hv), f64(b.z0);
      i32(b.nc), i32(b.ni), i32(b.nj), i32(b.nk);
    }
    for (const Block& b : blocks)
      for (int i = 0; i < b.ni; ++i)
        for (int j = 0; j < b.nj; ++j)
          for (int k = 0; k < b.nk; ++k)
            for (double v : b.value(i, j, k)) precision == 8 ? f64(v) : f32(float(v));
    return out_;
  }

 private:
  void put(const void* p, size_t n) {
    std::string s(static_cast<const char*>(p), n);
    if (big_endian) std::reverse(s.begin(), s.end());
    out_ += s;
  }
  void i32(int32_t v) { put(&v, 4); }
  void f32(float v) { put(&v, 4); }
  void f64(double v) { put(&v, 8); }
  std::string out_;
};

}  // namespace weaver
