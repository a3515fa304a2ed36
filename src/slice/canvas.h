// Where `weaver slice` draws: a PNG picture (an Image, encoded at the end)
// or an SVG document (streamed to its file as it is drawn, so its size in
// memory does not grow with the elements drawn).  Coordinates are pixels from
// the top-left corner; text is the 5 x 7 font's, `scale` pixels a dot.
#pragma once

#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "export/output_file.h"
#include "schema/status.h"
#include "slice/png.h"

namespace weaver {

// viridis, sampled at 10 points (t = 0, 1/9, ..., 1) and interpolated.
Rgb colormap(double t);

class Canvas {
 public:
  enum class Align { kLeft, kCenter, kRight };
  virtual ~Canvas() = default;
  // The rectangle x0 <= x < x1, y0 <= y < y1, filled, with a border if
  // `border` (the mesh's element outlines).
  virtual void rect(double x0, double y0, double x1, double y1, Rgb fill, bool border) = 0;
  virtual void text(double x, double y, const std::string& s, int scale, Rgb c, Align a) = 0;
  // Writes the rest of the document, with the notes (key, text), to the file
  // given at creation: the first error of the whole drawing, if any.
  virtual Status finish(const std::vector<std::pair<std::string, std::string>>& notes) = 0;
};

// Both write into `file`, which must be open and outlive them.
std::unique_ptr<Canvas> png_canvas(int width, int height, OutputFile* file);
std::unique_ptr<Canvas> svg_canvas(int width, int height, OutputFile* file);

inline constexpr Rgb kOutline{40, 40, 40};
// The ground line on vertical sections of a mesh under a surface.
inline constexpr Rgb kGroundLine{20, 20, 20};

}  // namespace weaver
