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
  PngCanvas(int w, int h, OutputFile* file) : image_(w, h, {255, 255, 255}), file_(file) {}
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
  Status finish(const std::vector<std::pair<std::string, std::string>>& notes) override {
    const std::string png = encode_png(image_, notes);
    return file_->write_at(0, png.data(), png.size());
  }

 private:
  Image image_;
  OutputFile* file_;
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
  SvgCanvas(int w, int h, OutputFile* file) : out_(*file, 0) {
    put("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" "
        "width=\"" +
        std::to_string(w) + "\" height=\"" + std::to_string(h) + "\" viewBox=\"0 0 " +
        std::to_string(w) + " " + std::to_string(h) + "\">\n" +
        "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n");
  }
  void rect(double x0, double y0, double x1, double y1, Rgb fill, bool border) override {
    put("<rect x=\"" + num(x0) + "\" y=\"" + num(y0) + "\" width=\"" + num(x1 - x0) +
        "\" height=\"" + num(y1 - y0) + "\" fill=\"" + hex(fill) + "\"" +
        (border ? " stroke=\"" + hex(kOutline) + "\" stroke-width=\"0.5\"/>\n" : "/>\n"));
  }
  void text(double x, double y, const std::string& s, int scale, Rgb c, Align a) override {
    static const char* const kAnchor[] = {"start", "middle", "end"};
    put("<text x=\"" + num(x) + "\" y=\"" + num(y + kGlyphHeight * scale) +
        "\" font-family=\"monospace\" font-size=\"" + std::to_string(9 * scale) +
        "\" text-anchor=\"" + kAnchor[int(a)] + "\" fill=\"" + hex(c) + "\">" + s + "</text>\n");
  }
  Status finish(const std::vector<std::pair<std::string, std::string>>& notes) override {
    for (const auto& [k, v] : notes) put("<desc id=\"" + k + "\">" + v + "</desc>\n");
    put("</svg>\n");
    if (status_.ok()) status_ = out_.flush();
    return status_;
  }

 private:
  // Drawing calls cannot fail; the first write error is kept for finish().
  void put(const std::string& s) {
    if (status_.ok()) status_ = out_.put(s.data(), s.size());
  }

  Section out_;
  Status status_ = Status::Ok();
};

}  // namespace

std::unique_ptr<Canvas> png_canvas(int width, int height, OutputFile* file) {
  return std::make_unique<PngCanvas>(width, height, file);
}
std::unique_ptr<Canvas> svg_canvas(int width, int height, OutputFile* file) {
  return std::make_unique<SvgCanvas>(width, height, file);
}

}  // namespace weaver
