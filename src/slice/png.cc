#include "slice/png.h"

#include <algorithm>
#include <array>

#include "slice/font.h"

namespace weaver {

Image::Image(int width, int height, Rgb background)
    : width_(width), height_(height), rgb_(size_t(width) * size_t(height) * 3) {
  fill(0, 0, width, height, background);
}

void Image::set(int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
  uint8_t* p = &rgb_[(size_t(y) * size_t(width_) + size_t(x)) * 3];
  p[0] = c.r, p[1] = c.g, p[2] = c.b;
}

Rgb Image::get(int x, int y) const {
  const uint8_t* p = &rgb_[(size_t(y) * size_t(width_) + size_t(x)) * 3];
  return {p[0], p[1], p[2]};
}

void Image::fill(int x0, int y0, int x1, int y1, Rgb c) {
  x0 = std::max(x0, 0), y0 = std::max(y0, 0);
  x1 = std::min(x1, width_), y1 = std::min(y1, height_);
  for (int y = y0; y < y1; ++y) {
    uint8_t* p = &rgb_[(size_t(y) * size_t(width_) + size_t(x0)) * 3];
    for (int x = x0; x < x1; ++x, p += 3) p[0] = c.r, p[1] = c.g, p[2] = c.b;
  }
}

void Image::frame(int x0, int y0, int x1, int y1, Rgb c) {
  fill(x0, y0, x1, y0 + 1, c);
  fill(x0, y1 - 1, x1, y1, c);
  fill(x0, y0, x0 + 1, y1, c);
  fill(x1 - 1, y0, x1, y1, c);
}

void Image::text(int x, int y, const std::string& s, int scale, Rgb c) {
  for (size_t i = 0; i < s.size(); ++i) {
    const int gx = x + int(i) * (kGlyphWidth + 1) * scale;
    for (int row = 0; row < kGlyphHeight; ++row)
      for (int col = 0; col < kGlyphWidth; ++col) {
        if (glyph_pixel(s[i], col, row)) {
          fill(gx + col * scale, y + row * scale, gx + (col + 1) * scale, y + (row + 1) * scale, c);
        }
      }
  }
}

uint32_t crc32(const uint8_t* data, size_t n, uint32_t crc) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (size_t i = 0; i < n; ++i) crc = table[(crc ^ data[i]) & 0xff] ^ (crc >> 8);
  return ~crc;
}

uint32_t adler32(const uint8_t* data, size_t n, uint32_t adler) {
  uint32_t a = adler & 0xffff, b = adler >> 16;
  while (n > 0) {
    const size_t chunk = std::min<size_t>(n, 5552);  // no overflow before the modulo
    for (size_t i = 0; i < chunk; ++i) a += data[i], b += a;
    a %= 65521, b %= 65521;
    data += chunk, n -= chunk;
  }
  return (b << 16) | a;
}

namespace {

// Bits into bytes, least significant bit first (RFC 1951, 3.1.1).
class BitWriter {
 public:
  void bits(uint32_t value, int count) {
    acc_ |= uint64_t(value) << used_;
    used_ += count;
    while (used_ >= 8) out_ += char(acc_ & 0xff), acc_ >>= 8, used_ -= 8;
  }
  // A Huffman code: its bits go most significant first.
  void code(uint32_t code, int length) {
    uint32_t reversed = 0;
    for (int i = 0; i < length; ++i) reversed |= ((code >> i) & 1) << (length - 1 - i);
    bits(reversed, length);
  }
  std::string finish() {
    if (used_ > 0) out_ += char(acc_ & 0xff);
    return std::move(out_);
  }

 private:
  std::string out_;
  uint64_t acc_ = 0;
  int used_ = 0;
};

// The fixed literal/length code of symbol 0..287.
void fixed_symbol(BitWriter& w, int sym) {
  if (sym < 144) return w.code(0x30 + sym, 8);
  if (sym < 256) return w.code(0x190 + (sym - 144), 9);
  if (sym < 280) return w.code(sym - 256, 7);
  w.code(0xC0 + (sym - 280), 8);
}

// A match of `length` (3..258) bytes at distance 1.
void run(BitWriter& w, int length) {
  static constexpr int kBase[29] = {3,  4,  5,  6,  7,  8,  9,  10, 11,  13,  15,  17,  19,  23, 27,
                                    31, 35, 43, 51, 59, 67, 83, 99, 115, 131, 163, 195, 227, 258};
  static constexpr int kExtra[29] = {0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2,
                                     2, 3, 3, 3, 3, 4, 4, 4, 4, 5, 5, 5, 5, 0};
  int i = 28;
  while (kBase[i] > length) --i;
  fixed_symbol(w, 257 + i);
  if (kExtra[i] > 0) w.bits(uint32_t(length - kBase[i]), kExtra[i]);
  w.code(0, 5);  // distance code 0: distance 1
}

void chunk(std::string* png, const char* type, const std::string& data) {
  const uint32_t n = uint32_t(data.size());
  const char len[4] = {char(n >> 24), char(n >> 16), char(n >> 8), char(n)};
  png->append(len, 4);
  std::string body = std::string(type, 4) + data;
  png->append(body);
  const uint32_t c = crc32(reinterpret_cast<const uint8_t*>(body.data()), body.size());
  const char crc[4] = {char(c >> 24), char(c >> 16), char(c >> 8), char(c)};
  png->append(crc, 4);
}

std::string be32(uint32_t v) { return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)}; }

}  // namespace

std::string zlib_compress(const std::vector<uint8_t>& data) {
  BitWriter w;
  w.bits(1, 1);  // BFINAL
  w.bits(1, 2);  // BTYPE 01: fixed Huffman codes
  size_t i = 0;
  while (i < data.size()) {
    size_t n = 0;
    if (i > 0) {
      while (i + n < data.size() && n < 258 && data[i + n] == data[i - 1]) ++n;
    }
    if (n >= 3) {
      run(w, int(n));
      i += n;
    } else {
      fixed_symbol(w, data[i++]);
    }
  }
  fixed_symbol(w, 256);  // end of block
  const uint32_t adler = adler32(data.data(), data.size());
  return std::string("\x78\x01", 2) + w.finish() + be32(adler);
}

std::string encode_png(const Image& image,
                       const std::vector<std::pair<std::string, std::string>>& text,
                       const Rgb* transparent) {
  const size_t stride = size_t(image.width()) * 3;
  std::vector<uint8_t> filtered;
  filtered.reserve((stride + 1) * size_t(image.height()));
  std::vector<uint8_t> sub(stride), up(stride);
  const uint8_t* rgb = image.rgb().data();
  for (int y = 0; y < image.height(); ++y) {
    const uint8_t* row = rgb + size_t(y) * stride;
    const uint8_t* above = y > 0 ? row - stride : nullptr;
    size_t sub_zeros = 0, up_zeros = 0;
    for (size_t i = 0; i < stride; ++i) {
      sub[i] = uint8_t(row[i] - (i >= 3 ? row[i - 3] : 0));
      up[i] = uint8_t(row[i] - (above ? above[i] : 0));
      sub_zeros += sub[i] == 0, up_zeros += up[i] == 0;
    }
    const bool use_up = up_zeros > sub_zeros;
    filtered.push_back(use_up ? 2 : 1);
    filtered.insert(filtered.end(), (use_up ? up : sub).begin(), (use_up ? up : sub).end());
  }
  std::string png("\x89PNG\r\n\x1a\n", 8);
  std::string ihdr = be32(uint32_t(image.width())) + be32(uint32_t(image.height()));
  ihdr += std::string("\x08\x02\x00\x00\x00", 5);  // 8-bit RGB, deflate, no interlace
  chunk(&png, "IHDR", ihdr);
  if (transparent) {  // three 16-bit samples, as the bit depth is 8
    const Rgb& c = *transparent;
    chunk(&png, "tRNS", std::string{'\0', char(c.r), '\0', char(c.g), '\0', char(c.b)});
  }
  for (const auto& [key, value] : text) chunk(&png, "tEXt", key + std::string(1, '\0') + value);
  chunk(&png, "IDAT", zlib_compress(filtered));
  chunk(&png, "IEND", "");
  return png;
}

}  // namespace weaver
