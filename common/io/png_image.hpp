#pragma once
// A small RGB raster for pictures of voxels (one pixel block per voxel)
// and a PNG writer (zlib deflate). Charts are drawn by `python3 -m msfab report`.
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
  // std::runtime_error naming the path if it cannot be written.
  void write_png(const std::string& path) const;

 private:
  int w_, h_;
  std::vector<std::uint8_t> rgb_;
};

}  // namespace msfab
