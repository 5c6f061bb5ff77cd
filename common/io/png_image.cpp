#include "io/png_image.hpp"

#include <zlib.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "io/atomic_file.hpp"

namespace msfab {
namespace {

// 3 x 5 glyphs, rows top to bottom, 3 bits per row (leftmost = 4).
std::array<std::uint16_t, 5> glyph(char c) {
  switch (std::toupper(static_cast<unsigned char>(c))) {
    case '0': return {7, 5, 5, 5, 7};
    case '1': return {2, 6, 2, 2, 7};
    case '2': return {7, 1, 7, 4, 7};
    case '3': return {7, 1, 7, 1, 7};
    case '4': return {5, 5, 7, 1, 1};
    case '5': return {7, 4, 7, 1, 7};
    case '6': return {7, 4, 7, 5, 7};
    case '7': return {7, 1, 1, 1, 1};
    case '8': return {7, 5, 7, 5, 7};
    case '9': return {7, 5, 7, 1, 7};
    case 'A': return {2, 5, 7, 5, 5};
    case 'B': return {6, 5, 6, 5, 6};
    case 'C': return {3, 4, 4, 4, 3};
    case 'D': return {6, 5, 5, 5, 6};
    case 'E': return {7, 4, 6, 4, 7};
    case 'F': return {7, 4, 6, 4, 4};
    case 'G': return {3, 4, 5, 5, 3};
    case 'H': return {5, 5, 7, 5, 5};
    case 'I': return {7, 2, 2, 2, 7};
    case 'J': return {1, 1, 1, 5, 2};
    case 'K': return {5, 5, 6, 5, 5};
    case 'L': return {4, 4, 4, 4, 7};
    case 'M': return {5, 7, 7, 5, 5};
    case 'N': return {6, 5, 5, 5, 5};
    case 'O': return {2, 5, 5, 5, 2};
    case 'P': return {6, 5, 6, 4, 4};
    case 'Q': return {2, 5, 5, 6, 3};
    case 'R': return {6, 5, 6, 5, 5};
    case 'S': return {3, 4, 2, 1, 6};
    case 'T': return {7, 2, 2, 2, 2};
    case 'U': return {5, 5, 5, 5, 7};
    case 'V': return {5, 5, 5, 5, 2};
    case 'W': return {5, 5, 7, 7, 5};
    case 'X': return {5, 5, 2, 5, 5};
    case 'Y': return {5, 5, 2, 2, 2};
    case 'Z': return {7, 1, 2, 4, 7};
    case '.': return {0, 0, 0, 0, 2};
    case ',': return {0, 0, 0, 2, 4};
    case '-': return {0, 0, 7, 0, 0};
    case '+': return {0, 2, 7, 2, 0};
    case '=': return {0, 7, 0, 7, 0};
    case ':': return {0, 2, 0, 2, 0};
    case '/': return {1, 1, 2, 4, 4};
    case '(': return {1, 2, 2, 2, 1};
    case ')': return {4, 2, 2, 2, 4};
    case '_': return {0, 0, 0, 0, 7};
    default: return {0, 0, 0, 0, 0};
  }
}

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<std::uint8_t>(v >> s));
}

void chunk(std::vector<std::uint8_t>& out, const char* type, const std::vector<std::uint8_t>& data) {
  put_u32(out, static_cast<std::uint32_t>(data.size()));
  const std::size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data.begin(), data.end());
  const uLong crc = crc32(0L, out.data() + start, static_cast<uInt>(out.size() - start));
  put_u32(out, static_cast<std::uint32_t>(crc));
}

}  // namespace

PngImage::PngImage(int width, int height, Rgb background) : w_(width), h_(height) {
  if (width < 1 || height < 1) throw std::invalid_argument("PngImage: empty image");
  rgb_.resize(std::size_t(width) * height * 3);
  for (std::size_t i = 0; i < rgb_.size(); i += 3) std::copy(background.begin(), background.end(), rgb_.begin() + i);
}

void PngImage::set(int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= w_ || y >= h_) return;
  std::copy(c.begin(), c.end(), rgb_.begin() + 3 * (std::size_t(y) * w_ + x));
}

Rgb PngImage::get(int x, int y) const {
  const std::size_t i = 3 * (std::size_t(y) * w_ + x);
  return {rgb_[i], rgb_[i + 1], rgb_[i + 2]};
}

void PngImage::line(double x0, double y0, double x1, double y1, Rgb c) {
  const int steps = static_cast<int>(std::ceil(std::max(std::abs(x1 - x0), std::abs(y1 - y0)))) + 1;
  for (int s = 0; s <= steps; ++s) {
    const double t = double(s) / steps;
    set(static_cast<int>(std::lround(x0 + t * (x1 - x0))), static_cast<int>(std::lround(y0 + t * (y1 - y0))), c);
  }
}

void PngImage::disc(double x, double y, double r, Rgb c) {
  for (int j = static_cast<int>(std::floor(y - r)); j <= static_cast<int>(std::ceil(y + r)); ++j)
    for (int i = static_cast<int>(std::floor(x - r)); i <= static_cast<int>(std::ceil(x + r)); ++i)
      if ((i - x) * (i - x) + (j - y) * (j - y) <= r * r) set(i, j, c);
}

int PngImage::text(int x, int y, const std::string& s, Rgb c, int scale) {
  for (std::size_t n = 0; n < s.size(); ++n) {
    const auto g = glyph(s[n]);
    for (int row = 0; row < 5; ++row)
      for (int col = 0; col < 3; ++col)
        if (g[row] >> (2 - col) & 1)
          for (int dy = 0; dy < scale; ++dy)
            for (int dx = 0; dx < scale; ++dx)
              set(x + static_cast<int>(n) * 4 * scale + col * scale + dx, y + row * scale + dy, c);
  }
  return text_width(s, scale);
}

void PngImage::write_png(const std::string& path) const {
  std::vector<std::uint8_t> raw;
  raw.reserve(std::size_t(h_) * (3 * w_ + 1));
  for (int y = 0; y < h_; ++y) {
    raw.push_back(0);  // filter: none
    raw.insert(raw.end(), rgb_.begin() + 3 * std::size_t(y) * w_, rgb_.begin() + 3 * std::size_t(y + 1) * w_);
  }
  uLongf packed_size = compressBound(static_cast<uLong>(raw.size()));
  std::vector<std::uint8_t> packed(packed_size);
  if (compress2(packed.data(), &packed_size, raw.data(), static_cast<uLong>(raw.size()), 9) != Z_OK)
    throw std::runtime_error(path + ": PNG compression failed");
  packed.resize(packed_size);
  std::vector<std::uint8_t> out = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<std::uint8_t> header;
  put_u32(header, static_cast<std::uint32_t>(w_));
  put_u32(header, static_cast<std::uint32_t>(h_));
  header.insert(header.end(), {8, 2, 0, 0, 0});  // 8-bit RGB, deflate, no filter choice, no interlace
  chunk(out, "IHDR", header);
  chunk(out, "IDAT", packed);
  chunk(out, "IEND", {});
  AtomicFile file(path);
  file.write(out.data(), out.size());
  file.commit();
}

}  // namespace msfab
