// Where `weaver slice` draws: a PNG picture (an Image, encoded at the end)
// or an SVG document (written as it is drawn).  Coordinates are pixels from
// the top-left corner; text is the 5 x 7 font's, `scale` pixels a dot.
#pragma once

#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

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
  // The finished document.
  virtual std::string finish(const std::vector<std::pair<std::string, std::string>>& notes) = 0;
};

std::unique_ptr<Canvas> png_canvas(int width, int height);
std::unique_ptr<Canvas> svg_canvas(int width, int height);

inline constexpr Rgb kOutline{40, 40, 40};

}  // namespace weaver
