#include "gamut_plots.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <limits>

#include "io/chart.hpp"

namespace msfab {

namespace {
// One colour per SampleStep (initial, discrete, continuous, void variant, directed, targeted).
const Rgb kStepColors[6] = {{150, 150, 150}, {40, 90, 200}, {220, 40, 40}, {140, 60, 170}, {30, 160, 60}, {230, 140, 20}};

// The step's name as the chart font writes it (capitals, no underscores).
std::string step_label(int step) {
  std::string label = step_name(static_cast<SampleStep>(step));
  for (char& ch : label) ch = ch == '_' ? ' ' : static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  return label;
}

// Structures as points coloured by the step that found them; the legend
// lists the steps present.
void plot_structures(Chart& chart, const MicrostructureSet& set,
                     const std::function<std::pair<double, double>(const Microstructure&)>& at) {
  std::vector<std::pair<std::string, Rgb>> legend;
  for (int step = 0; step < 6; ++step) {
    std::vector<double> x, y;
    for (const Microstructure& m : set.items)
      if (static_cast<int>(m.step) == step) {
        const auto [a, b] = at(m);
        x.push_back(a), y.push_back(b);
      }
    if (x.empty()) continue;
    chart.points(x, y, kStepColors[step], 2.0);
    legend.emplace_back(step_label(step), kStepColors[step]);
  }
  chart.legend(legend);
}
}  // namespace

void plot_gamut_projection(const std::string& path, const MicrostructureSet& set, const GamutLevelSet& gamut,
                           const MaterialSpace& space, const std::string& title) {
  const bool ortho = space.kind() == MaterialSpaceKind::orthotropic2d;
  const int iE = 0, inu = ortho ? 2 : 1;
  const double nu_hi = space.kind() == MaterialSpaceKind::cubic3d ? 0.5 : 1.0;
  ChartAxes axes;
  axes.x0 = -1, axes.x1 = nu_hi, axes.y0 = -set.decades, axes.y1 = 0.25;
  axes.x_label = ortho ? "POISSON RATIO NU_XY" : "POISSON RATIO NU";
  axes.y_label = ortho ? "LOG10 EX/E_STIFF" : "LOG10 E/E_STIFF";
  axes.title = title;
  Chart chart(720, 560, axes);

  // min Phi over the other coordinates, per (E node, nu node).
  const int d = gamut.dimension(), n = gamut.cells();
  std::vector<double> table(std::size_t(n) * n, std::numeric_limits<double>::infinity());
  const std::vector<double>& phi = gamut.values();
  for (std::size_t v = 0; v < phi.size(); ++v) {
    long long flat = static_cast<long long>(v);
    int a = 0, b = 0;
    for (int k = 0; k < d; ++k) {
      const int idx = static_cast<int>(flat % n);
      flat /= n;
      if (k == iE) a = idx;
      if (k == inu) b = idx;
    }
    double& t = table[std::size_t(a) * n + b];
    t = std::min(t, phi[v]);
  }
  auto node_coord = [&](double u) { return std::clamp((u - gamut.lower()) / gamut.spacing() - 0.5, 0.0, n - 1.000001); };
  VecX probe = VecX::Constant(space.dimension(), 0.5);
  chart.contour(
      [&](double nu, double logE) {
        probe[iE] = std::pow(10.0, logE) * set.E_stiff;
        probe[inu] = nu;
        const VecX u = space.normalize(probe);
        const double s = node_coord(u[iE]), t = node_coord(u[inu]);
        const int s0 = static_cast<int>(s), t0 = static_cast<int>(t);
        const double fs = s - s0, ft = t - t0;
        auto at = [&](int i, int j) { return table[std::size_t(i) * n + j]; };
        return (1 - fs) * ((1 - ft) * at(s0, t0) + ft * at(s0, t0 + 1)) + fs * ((1 - ft) * at(s0 + 1, t0) + ft * at(s0 + 1, t0 + 1));
      },
      {0, 0, 0});

  plot_structures(chart, set, [&](const Microstructure& m) {
    return std::make_pair(m.properties[inu], std::log10(m.properties[iE] / set.E_stiff));
  });
  chart.write(path);
}


void plot_shear_projections(const std::string& stem, const MicrostructureSet& set, const MaterialSpace& space) {
  if (space.kind() == MaterialSpaceKind::orthotropic2d) return;
  const double nu_hi = space.kind() == MaterialSpaceKind::cubic3d ? 0.5 : 1.0;
  auto g_ratio = [](const Microstructure& m) { return 2 * (1 + m.properties[1]) * m.properties[2] / m.properties[0]; };
  double top = 1;
  for (const Microstructure& m : set.items) top = std::max(top, g_ratio(m));
  const double g_hi = std::ceil(1.05 * top);
  {
    ChartAxes axes;
    axes.x0 = 0, axes.x1 = g_hi, axes.y0 = -set.decades, axes.y1 = 0.25;
    axes.x_label = "RELATIVE SHEAR MODULUS 2(1+NU)G/E";
    axes.y_label = "LOG10 E/E_STIFF";
    axes.title = "E AGAINST RELATIVE SHEAR MODULUS, " + std::to_string(set.items.size()) + " STRUCTURES";
    Chart chart(720, 560, axes);
    plot_structures(chart, set, [&](const Microstructure& m) {
      return std::make_pair(g_ratio(m), std::log10(m.properties[0] / set.E_stiff));
    });
    chart.write(stem + "_E_G.png");
  }
  {
    ChartAxes axes;
    axes.x0 = -1, axes.x1 = nu_hi, axes.y0 = 0, axes.y1 = g_hi;
    axes.x_label = "POISSON RATIO NU";
    axes.y_label = "RELATIVE SHEAR MODULUS 2(1+NU)G/E";
    axes.title = "RELATIVE SHEAR MODULUS AGAINST NU, " + std::to_string(set.items.size()) + " STRUCTURES";
    Chart chart(720, 560, axes);
    plot_structures(chart, set, [&](const Microstructure& m) { return std::make_pair(m.properties[1], g_ratio(m)); });
    chart.write(stem + "_nu_G.png");
  }
}

void plot_coverage(const std::string& path, const std::vector<GamutCycle>& history) {
  ChartAxes axes;
  double top = 0;
  for (const GamutCycle& c : history) top = std::max(top, c.coverage);
  axes.x0 = 0, axes.x1 = std::max<double>(1, history.empty() ? 1 : history.back().cycle);
  axes.y0 = 0, axes.y1 = top > 0 ? 1.1 * top : 1;
  axes.x_label = "CYCLE";
  axes.y_label = "COVERAGE (FRACTION OF THE UNIT CUBE INSIDE THE GAMUT)";
  axes.title = "GAMUT COVERAGE PER CYCLE";
  Chart chart(640, 420, axes);
  std::vector<double> x, y;
  for (const GamutCycle& c : history) x.push_back(c.cycle), y.push_back(c.coverage);
  chart.polyline(x, y, {40, 90, 200});
  chart.write(path);
}

}  // namespace msfab
