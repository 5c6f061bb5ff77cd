#pragma once
// A small RGB raster with the drawing the toolkit's plots need (pixels,
// lines, discs, a 3 x 5 block font) and a PNG writer (zlib deflate).
// Written atomically like every output: "<path>.tmp", then renamed.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace msfab {

using Rgb = std::array<std::uint8_t, 3>;

class PngImage {
 public:
  PngImage(int width, int height, Rgb background = {255, 255, 255});
  int width() const { return w_; }
  int height() const { return h_; }
  // (x, y) with y down; out-of-range pixels are ignored.
  void set(int x, int y, Rgb color);
  Rgb get(int x, int y) const;
  void line(double x0, double y0, double x1, double y1, Rgb color);
  void disc(double x, double y, double radius, Rgb color);
  // Upper-case letters, digits and " .,-+=:/()_"; other characters draw as
  // blanks. Each glyph is 3 x 5 blocks of `scale` pixels; returns the width.
  int text(int x, int y, const std::string& s, Rgb color, int scale = 2);
  static int text_width(const std::string& s, int scale = 2) { return static_cast<int>(s.size()) * 4 * scale; }
  // std::runtime_error naming the path if it cannot be written.
  void write_png(const std::string& path) const;

 private:
  int w_, h_;
  std::vector<std::uint8_t> rgb_;
};

}  // namespace msfab
