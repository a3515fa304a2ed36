// A picture in memory and its PNG encoding, written by weaver itself: 8-bit
// RGB, rows filtered (Sub or Up, whichever leaves more zero bytes), one
// deflate block with the fixed Huffman codes whose only matches are runs
// (distance 1: flat colour after filtering is a run of zeros), CRC-32 per
// chunk and Adler-32 over the stream (RFC 1950, 1951; PNG 1.2).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace weaver {

struct Rgb {
  uint8_t r = 0, g = 0, b = 0;
  friend bool operator==(const Rgb&, const Rgb&) = default;
};

class Image {
 public:
  Image(int width, int height, Rgb background);
  int width() const { return width_; }
  int height() const { return height_; }
  // Pixels outside the image are ignored.
  void set(int x, int y, Rgb c);
  Rgb get(int x, int y) const;
  // The pixels x0 <= x < x1, y0 <= y < y1 (clipped).
  void fill(int x0, int y0, int x1, int y1, Rgb c);
  // The border of that rectangle, one pixel wide.
  void frame(int x0, int y0, int x1, int y1, Rgb c);
  // Text in the 5 x 7 font, top-left corner at (x, y), each font pixel
  // scale x scale.
  void text(int x, int y, const std::string& s, int scale, Rgb c);
  const std::vector<uint8_t>& rgb() const { return rgb_; }

 private:
  int width_, height_;
  std::vector<uint8_t> rgb_;
};

// The PNG file of the image, with tEXt chunks (keyword, text).  With
// transparent, the pixels of exactly that colour are transparent (a tRNS
// chunk: every PNG reader honours it, and the pixels stay RGB).
std::string encode_png(const Image& image,
                       const std::vector<std::pair<std::string, std::string>>& text,
                       const Rgb* transparent = nullptr);

uint32_t crc32(const uint8_t* data, size_t n, uint32_t crc = 0);
uint32_t adler32(const uint8_t* data, size_t n, uint32_t adler = 1);
// A zlib stream of data (fixed Huffman codes, runs as matches).
std::string zlib_compress(const std::vector<uint8_t>& data);

}  // namespace weaver
