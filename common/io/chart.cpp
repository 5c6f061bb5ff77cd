#include "io/chart.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace msfab {
namespace {
constexpr Rgb kInk = {0, 0, 0};
constexpr Rgb kGrid = {225, 225, 225};

std::string tick_label(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", std::abs(v) < 1e-12 ? 0.0 : v);
  return buf;
}
}  // namespace

Chart::Chart(int width, int height, const ChartAxes& axes)
    : image_(width, height), axes_(axes), left_(70), right_(width - 20), top_(40), bottom_(height - 50) {
  if (!(axes.x1 > axes.x0) || !(axes.y1 > axes.y0) || right_ - left_ < 50 || bottom_ - top_ < 50)
    throw std::invalid_argument("Chart: empty range or too small an image");
  frame();
}

double Chart::px(double x) const { return left_ + (x - axes_.x0) / (axes_.x1 - axes_.x0) * (right_ - left_); }
double Chart::py(double y) const { return bottom_ - (y - axes_.y0) / (axes_.y1 - axes_.y0) * (bottom_ - top_); }

void Chart::frame() {
  for (int t = 0; t <= 4; ++t) {
    const double x = axes_.x0 + t * (axes_.x1 - axes_.x0) / 4, y = axes_.y0 + t * (axes_.y1 - axes_.y0) / 4;
    image_.line(px(x), top_, px(x), bottom_, kGrid);
    image_.line(left_, py(y), right_, py(y), kGrid);
    const std::string xs = tick_label(x), ys = tick_label(y);
    image_.text(static_cast<int>(px(x)) - PngImage::text_width(xs) / 2, bottom_ + 8, xs, kInk);
    image_.text(left_ - 8 - PngImage::text_width(ys), static_cast<int>(py(y)) - 5, ys, kInk);
  }
  image_.line(left_, top_, left_, bottom_, kInk);
  image_.line(left_, bottom_, right_, bottom_, kInk);
  image_.line(right_, top_, right_, bottom_, kInk);
  image_.line(left_, top_, right_, top_, kInk);
  image_.text((left_ + right_ - PngImage::text_width(axes_.x_label)) / 2, bottom_ + 28, axes_.x_label, kInk);
  image_.text(8, top_ - 22, axes_.y_label, kInk);
  image_.text((left_ + right_ - PngImage::text_width(axes_.title)) / 2, 8, axes_.title, kInk);
}

void Chart::points(const std::vector<double>& x, const std::vector<double>& y, Rgb color, double radius) {
  for (std::size_t i = 0; i < x.size() && i < y.size(); ++i) {
    const double X = px(x[i]), Y = py(y[i]);
    if (X >= left_ && X <= right_ && Y >= top_ && Y <= bottom_) image_.disc(X, Y, radius, color);
  }
}

void Chart::polyline(const std::vector<double>& x, const std::vector<double>& y, Rgb color) {
  for (std::size_t i = 1; i < x.size() && i < y.size(); ++i) image_.line(px(x[i - 1]), py(y[i - 1]), px(x[i]), py(y[i]), color);
  points(x, y, color, 2.5);
}

void Chart::contour(const std::function<double(double, double)>& f, Rgb color) {
  const int w = right_ - left_ + 1, h = bottom_ - top_ + 1;
  std::vector<double> v(std::size_t(w) * h);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const double x = axes_.x0 + double(i) / (w - 1) * (axes_.x1 - axes_.x0);
      const double y = axes_.y1 - double(j) / (h - 1) * (axes_.y1 - axes_.y0);
      v[std::size_t(j) * w + i] = f(x, y);
    }
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const bool in = v[std::size_t(j) * w + i] <= 0;
      const bool edge = (i + 1 < w && (v[std::size_t(j) * w + i + 1] <= 0) != in) ||
                        (j + 1 < h && (v[std::size_t(j + 1) * w + i] <= 0) != in);
      if (edge) image_.set(left_ + i, top_ + j, color);
    }
}

void Chart::legend(const std::vector<std::pair<std::string, Rgb>>& entries) {
  int y = top_ + 8;
  for (const auto& [label, color] : entries) {
    image_.disc(right_ - 150, y + 5, 4, color);
    image_.text(right_ - 140, y, label, kInk);
    y += 16;
  }
}

}  // namespace msfab
