// A 5 x 7 pixel bitmap font for the labels of `weaver slice` pictures:
// digits, lower-case letters and the punctuation of numbers and units.
#pragma once

#include <string_view>

namespace weaver {

inline constexpr int kGlyphWidth = 5, kGlyphHeight = 7;

// Whether pixel (col, row) of character c's glyph is set (row 0 at the top).
// Characters without a glyph are blank.
bool glyph_pixel(char c, int col, int row);

// Width in pixels of text at `scale` (one blank column between glyphs).
inline int text_width(std::string_view text, int scale) {
  return text.empty() ? 0 : int(text.size()) * (kGlyphWidth + 1) * scale - scale;
}

}  // namespace weaver
