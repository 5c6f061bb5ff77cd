#pragma once
// Plots for the stages' reports: an x-y chart with axes, ticks, labels, a
// legend, scatter points, polylines and the zero contour of a function,
// written as PNG (io/png_image.hpp).
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "io/png_image.hpp"

namespace msfab {

struct ChartAxes {
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;  // data ranges shown
  std::string x_label, y_label, title;
};

class Chart {
 public:
  Chart(int width, int height, const ChartAxes& axes);
  // Data -> pixel coordinates of the plot area.
  double px(double x) const;
  double py(double y) const;
  void points(const std::vector<double>& x, const std::vector<double>& y, Rgb color, double radius = 2.0);
  void polyline(const std::vector<double>& x, const std::vector<double>& y, Rgb color);
  // Marks the pixels of the plot area where f changes sign (f's zero set).
  void contour(const std::function<double(double, double)>& f, Rgb color);
  void legend(const std::vector<std::pair<std::string, Rgb>>& entries);
  void write(const std::string& path) const { image_.write_png(path); }

 private:
  PngImage image_;
  ChartAxes axes_;
  int left_, right_, top_, bottom_;  // plot area in pixels
  void frame();
};

}  // namespace msfab
