#include "family_plots.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "families/beam_template.hpp"
#include "families/family_selection.hpp"
#include "io/chart.hpp"
#include "io/png_image.hpp"

namespace msfab {

namespace {

const Rgb kOther{170, 170, 170};
const Rgb kPalette[8] = {{220, 40, 40},  {40, 90, 200},  {30, 160, 60}, {230, 140, 20},
                         {150, 60, 190}, {20, 170, 180}, {200, 80, 140}, {110, 110, 40}};
Rgb family_color(int f) { return f < 0 ? kOther : kPalette[f % 8]; }

std::string family_label(int f) { return "FAMILY " + std::to_string(f + 1); }

// One scatter plot of the selected structures, family members in colour.
template <class X, class Y>
void scatter(const std::string& path, const FamiliesResult& r, ChartAxes axes, X x_of, Y y_of) {
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (std::size_t i = 0; i < r.selection.size(); ++i) {
    const double x = x_of(i), y = y_of(i);
    if (!std::isfinite(x) || !std::isfinite(y)) continue;
    x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
  }
  if (!(x1 >= x0)) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  const double mx = 0.05 * std::max(x1 - x0, 1e-9), my = 0.05 * std::max(y1 - y0, 1e-9);
  axes.x0 = x0 - mx, axes.x1 = x1 + mx, axes.y0 = y0 - my, axes.y1 = y1 + my;
  Chart chart(720, 560, axes);
  const int families = int(r.families.size());
  std::vector<std::pair<std::string, Rgb>> legend{{"OTHER", kOther}};
  for (int f = -1; f < families; ++f) {
    std::vector<double> xs, ys;
    for (std::size_t i = 0; i < r.selection.size(); ++i)
      if (r.family_of[i] == f && std::isfinite(x_of(i)) && std::isfinite(y_of(i))) xs.push_back(x_of(i)), ys.push_back(y_of(i));
    chart.points(xs, ys, family_color(f), f < 0 ? 1.5 : 2.5);
    if (f >= 0) legend.emplace_back(family_label(f), family_color(f));
  }
  chart.legend(legend);
  chart.write(path);
}

// A structure seen along z: each pixel's grey is the depth of the first
// solid voxel (near = dark), so beams in front read as darker than those
// behind; void through the whole cell is white.
void draw_depth_view(PngImage& image, int x0, int y0, int scale, const std::vector<int>& ids, int n) {
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      int depth = n;
      for (int k = 0; k < n; ++k)
        if (ids[std::size_t(i) + std::size_t(n) * (std::size_t(j) + std::size_t(n) * k)] != 0) {
          depth = k;
          break;
        }
      const std::uint8_t g = depth == n ? 255 : std::uint8_t(30 + 170 * depth / n);
      for (int a = 0; a < scale; ++a)
        for (int b = 0; b < scale; ++b) image.set(x0 + i * scale + a, y0 + (n - 1 - j) * scale + b, {g, g, g});
    }
}

// One layer of a structure: solid black, void white.
void draw_slice(PngImage& image, int x0, int y0, int scale, const std::vector<int>& ids, int n, int k) {
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const bool solid = ids[std::size_t(i) + std::size_t(n) * (std::size_t(j) + std::size_t(n) * k)] != 0;
      const std::uint8_t g = solid ? 30 : 255;
      for (int a = 0; a < scale; ++a)
        for (int b = 0; b < scale; ++b) image.set(x0 + i * scale + a, y0 + (n - 1 - j) * scale + b, {g, g, g});
    }
}

}  // namespace

std::string plot_folder_for(const std::string& out) {
  for (const std::string suffix : {".families.h5", ".h5"})
    if (out.size() > suffix.size() && out.compare(out.size() - suffix.size(), suffix.size(), suffix) == 0)
      return out.substr(0, out.size() - suffix.size()) + ".plots";
  return out + ".plots";
}

void write_family_plots(const std::string& folder, const FamiliesResult& r, const MicrostructureSet& set) {
  std::filesystem::create_directories(folder);
  const auto prop = [&](std::size_t i) -> const VecX& { return set.items[std::size_t(r.selection[i])].properties; };

  ChartAxes embedding;
  embedding.x_label = "ISOMAP COORDINATE 1";
  embedding.y_label = "ISOMAP COORDINATE 2";
  embedding.title = "EMBEDDING OF THE SELECTED STRUCTURES";
  const bool two = r.embedding.cols() >= 2;
  scatter(folder + "/embedding.png", r, embedding, [&](std::size_t i) { return r.embedding(Eigen::Index(i), 0); },
          [&](std::size_t i) { return two ? r.embedding(Eigen::Index(i), 1) : 0.0; });

  ChartAxes e_nu;
  e_nu.x_label = "POISSON RATIO NU";
  e_nu.y_label = "LOG10 E/E_STIFF";
  e_nu.title = "FAMILY COVERAGE: E AND NU";
  scatter(folder + "/coverage_E_nu.png", r, e_nu, [&](std::size_t i) { return prop(i)[1]; },
          [&](std::size_t i) { return std::log10(prop(i)[0] / set.E_stiff); });

  ChartAxes nu_g;
  nu_g.x_label = "POISSON RATIO NU";
  nu_g.y_label = "SHEAR MODULUS RATIO G' = 2G(1+NU)/E";
  nu_g.title = "FAMILY COVERAGE: NU AND G'";
  scatter(folder + "/coverage_nu_G.png", r, nu_g, [&](std::size_t i) { return prop(i)[1]; },
          [&](std::size_t i) { return shear_modulus_ratio(prop(i)[0], prop(i)[1], prop(i)[2]); });

  // Per family: representative (left) and its fitted template (right), at
  // the set's resolution, one pixel block per voxel: seen along z with
  // depth shading (top), and the layers z = n/4 and z = 0 (below), which
  // cut through the fundamental tetrahedron and the cell face.
  const int n = set.nx, scale = std::max(1, 192 / n), gap = 12, side = n * scale;
  for (std::size_t f = 0; f < r.families.size(); ++f) {
    const FamilyRecord& fam = r.families[f];
    PngImage image(2 * side + 3 * gap, 3 * side + 4 * gap, {255, 255, 255});
    const std::vector<int>& rep = set.items[std::size_t(fam.representative)].ids;
    std::vector<int> tpl;
    if (fam.representative_template.size() > 0)
      tpl = rasterize_template(template_from_parameters(fam.representative_template, fam.caps), n).ids;
    for (int col = 0; col < 2; ++col) {
      const std::vector<int>& ids = col == 0 ? rep : tpl;
      if (ids.empty()) continue;
      const int x0 = gap + col * (side + gap);
      draw_depth_view(image, x0, gap, scale, ids, n);
      draw_slice(image, x0, 2 * gap + side, scale, ids, n, n / 4);
      draw_slice(image, x0, 3 * gap + 2 * side, scale, ids, n, 0);
    }
    image.write_png(folder + "/family" + std::to_string(f + 1) + ".png");
  }
}

}  // namespace msfab
