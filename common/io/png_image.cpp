#include "io/png_image.hpp"

#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "io/atomic_file.hpp"

namespace msfab {
namespace {

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
