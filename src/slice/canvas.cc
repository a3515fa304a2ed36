#include "slice/canvas.h"

#include <algorithm>
#include <cmath>

#include "slice/font.h"

namespace weaver {

Rgb colormap(double t) {
  static constexpr Rgb kViridis[10] = {
      {68, 1, 84},    {72, 40, 120},  {62, 74, 137},  {49, 104, 142}, {38, 130, 142},
      {31, 158, 137}, {53, 183, 121}, {110, 206, 88}, {181, 222, 43}, {253, 231, 37}};
  t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0) * 9;
  const int i = std::min(8, int(t));
  const double f = t - i;
  auto mix = [&](uint8_t a, uint8_t b) { return uint8_t(std::lround(a + (b - a) * f)); };
  return {mix(kViridis[i].r, kViridis[i + 1].r), mix(kViridis[i].g, kViridis[i + 1].g),
          mix(kViridis[i].b, kViridis[i + 1].b)};
}

namespace {

double aligned_x(double x, const std::string& s, int scale, Canvas::Align a) {
  const int w = text_width(s, scale);
  return a == Canvas::Align::kLeft ? x : a == Canvas::Align::kCenter ? x - w / 2.0 : x - w;
}

class PngCanvas : public Canvas {
 public:
  PngCanvas(int w, int h) : image_(w, h, {255, 255, 255}) {}
  void rect(double x0, double y0, double x1, double y1, Rgb fill, bool border) override {
    const int a = int(std::lround(x0)), b = int(std::lround(y0));
    const int c = std::max(a + 1, int(std::lround(x1))), d = std::max(b + 1, int(std::lround(y1)));
    image_.fill(a, b, c, d, fill);
    // Outlines only where elements are large enough to show them, decided
    // on the true size so that equal elements all get one or none.
    if (border && x1 - x0 >= 6 && y1 - y0 >= 6) image_.frame(a, b, c, d, kOutline);
  }
  void text(double x, double y, const std::string& s, int scale, Rgb c, Align a) override {
    image_.text(int(std::lround(aligned_x(x, s, scale, a))), int(std::lround(y)), s, scale, c);
  }
  std::string finish(const std::vector<std::pair<std::string, std::string>>& notes) override {
    return encode_png(image_, notes);
  }

 private:
  Image image_;
};

std::string hex(Rgb c) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c.r, c.g, c.b);
  return buf;
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

class SvgCanvas : public Canvas {
 public:
  SvgCanvas(int w, int h) {
    doc_ =
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" "
        "width=\"" +
        std::to_string(w) + "\" height=\"" + std::to_string(h) + "\" viewBox=\"0 0 " +
        std::to_string(w) + " " + std::to_string(h) + "\">\n" +
        "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n";
  }
  void rect(double x0, double y0, double x1, double y1, Rgb fill, bool border) override {
    doc_ += "<rect x=\"" + num(x0) + "\" y=\"" + num(y0) + "\" width=\"" + num(x1 - x0) +
            "\" height=\"" + num(y1 - y0) + "\" fill=\"" + hex(fill) + "\"";
    doc_ += border ? " stroke=\"" + hex(kOutline) + "\" stroke-width=\"0.5\"/>\n" : "/>\n";
  }
  void text(double x, double y, const std::string& s, int scale, Rgb c, Align a) override {
    static const char* const kAnchor[] = {"start", "middle", "end"};
    doc_ += "<text x=\"" + num(x) + "\" y=\"" + num(y + kGlyphHeight * scale) +
            "\" font-family=\"monospace\" font-size=\"" + std::to_string(9 * scale) +
            "\" text-anchor=\"" + kAnchor[int(a)] + "\" fill=\"" + hex(c) + "\">" + s + "</text>\n";
  }
  std::string finish(const std::vector<std::pair<std::string, std::string>>& notes) override {
    for (const auto& [k, v] : notes) doc_ += "<desc id=\"" + k + "\">" + v + "</desc>\n";
    return doc_ + "</svg>\n";
  }

 private:
  std::string doc_;
};

}  // namespace

std::unique_ptr<Canvas> png_canvas(int width, int height) {
  return std::make_unique<PngCanvas>(width, height);
}
std::unique_ptr<Canvas> svg_canvas(int width, int height) {
  return std::make_unique<SvgCanvas>(width, height);
}

}  // namespace weaver
