#include "design_report.hpp"

#include <algorithm>
#include <cmath>

#include "io/chart.hpp"
#include "io/png_image.hpp"

namespace msfab {

Design make_design(TopologyObjective& objective, const OptimizationResult& r, double E_stiff, double decades) {
  const CellGrid& g = objective.grid();
  const CellMaterialModel& model = objective.model();
  Design d;
  d.space = model.design_space();
  d.property_names = model.design_names();
  d.E_stiff = E_stiff;
  d.decades = decades;
  d.dimension = g.dimension();
  d.nx = g.nx(), d.ny = g.ny(), d.nz = g.nz();
  d.cell_size = g.h();
  d.roles = objective.setup().roles;
  const int n = int(d.property_names.size());
  const int k = int(model.family_names().size());
  d.unit = MatX::Zero(g.cells(), n);
  d.raw = MatX::Zero(g.cells(), n);
  d.phi = VecX::Zero(g.cells());
  if (k > 0) {
    d.family_names = model.family_names();
    d.family_unit = MatX::Zero(g.cells(), k);
    d.family_raw = MatX::Zero(g.cells(), k);
  }
  for (std::int64_t c = 0; c < g.cells(); ++c)
    if (d.roles[c] == CellRole::solid) d.unit(c, n - 1) = d.raw(c, n - 1) = 1.0;
  const MatX p = objective.physical(r.q);
  for (std::size_t i = 0; i < objective.design_cells().size(); ++i) {
    const std::int64_t c = objective.design_cells()[i];
    const VecX pc = p.row(Eigen::Index(i)).transpose();
    VecX unit, raw;
    model.design_row(pc, unit, raw);
    d.unit.row(c) = unit.transpose();
    d.raw.row(c) = raw.transpose();
    d.phi[c] = model.constraint(pc, nullptr);
    if (k > 0) {
      d.family_unit.row(c) = pc.head(k).transpose();
      d.family_raw.row(c) = model.raw(pc).head(k).transpose();
    }
  }
  objective.evaluate(r.q, nullptr);
  const VecX u = objective.grid_displacement(0);
  d.displacement = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      u.data(), g.nodes(), g.dimension());
  d.history = r.history;
  return d;
}

namespace {

// "out/x.design.h5" -> "out/x".
std::string artifact_stem(const std::string& artifact) {
  std::string stem = artifact;
  if (stem.size() > 3 && stem.compare(stem.size() - 3, 3, ".h5") == 0) stem.resize(stem.size() - 3);
  if (stem.size() > 7 && stem.compare(stem.size() - 7, 7, ".design") == 0) stem.resize(stem.size() - 7);
  return stem;
}

}  // namespace

std::string write_convergence_plot(const std::string& artifact, const OptimizationResult& r, const std::string& space) {
  const std::string path = artifact_stem(artifact) + ".convergence.png";
  std::vector<double> it, elastic;
  for (const auto& h : r.history) it.push_back(h.iteration), elastic.push_back(h.elastic);
  if (it.empty()) it = {0}, elastic = {r.value.elastic};
  const double lo = *std::min_element(elastic.begin(), elastic.end());
  const double hi = *std::max_element(elastic.begin(), elastic.end());
  ChartAxes axes;
  axes.x0 = 0, axes.x1 = std::max(1.0, it.back());
  // A flat history (one iteration) still needs a visible range.
  const double pad = hi - lo > 1e-9 * std::abs(hi) ? 0.05 * (hi - lo) : 0.05 * std::abs(hi) + 1e-30;
  axes.y0 = lo - pad, axes.y1 = hi + pad;
  axes.x_label = "iteration";
  axes.y_label = "elastic objective";
  axes.title = "msfab-topopt convergence (" + space + ")";
  Chart chart(720, 480, axes);
  chart.polyline(it, elastic, {30, 90, 200});
  chart.points(it, elastic, {30, 90, 200}, 1.5);
  chart.write(path);
  return path;
}

}  // namespace msfab

namespace msfab {

std::string write_density_picture(const std::string& artifact, const Design& d) {
  const std::string path = artifact_stem(artifact) + ".density.png";
  const int rho = static_cast<int>(d.raw.cols()) - 1;  // density is the last parameter of every space
  const auto colour = [&](std::int64_t c, double density) -> Rgb {
    if (d.roles[std::size_t(c)] == CellRole::solid) return {30, 60, 160};
    if (d.roles[std::size_t(c)] == CellRole::empty) return {250, 225, 225};
    const auto grey = static_cast<std::uint8_t>(std::lround(255.0 * (1.0 - std::clamp(density, 0.0, 1.0))));
    return {grey, grey, grey};
  };
  const auto cell = [&](int i, int j, int k) { return i + std::int64_t(d.nx) * (j + std::int64_t(d.ny) * k); };
  // Views: (columns, rows, cell at (column, row from the bottom), depth).
  struct View {
    int width, height, depth;
    int axis;  // 0: top view (depth along z), 1: front view (depth along y)
  };
  std::vector<View> views;
  if (d.dimension == 2) views.push_back({d.nx, d.ny, 1, 0});
  else views = {{d.nx, d.nz, d.ny, 1}, {d.nx, d.ny, d.nz, 0}};  // front above top
  int total_height = 0;
  for (const View& v : views) total_height += v.height;
  const int scale = std::clamp(1200 / std::max(1, d.nx), 1, 12), gap = views.size() > 1 ? 16 : 0;
  PngImage image(d.nx * scale, total_height * scale + gap * int(views.size() - 1));
  int top = 0;
  for (const View& v : views) {
    for (int row = 0; row < v.height; ++row)
      for (int col = 0; col < v.width; ++col) {
        // The densest design cell along the viewing direction decides the
        // pixel; forced-solid cells only where no design cell is seen
        // through them (a bridge deck would hide the structure below).
        std::int64_t best = -1;
        double best_density = -1, best_rank = -2;
        for (int t = 0; t < v.depth; ++t) {
          const std::int64_t c = v.axis == 0 ? cell(col, row, t) : cell(col, t, row);
          const CellRole role = d.roles[std::size_t(c)];
          const double rank = role == CellRole::empty ? -1.0 : role == CellRole::solid ? -0.5 : d.raw(c, rho);
          if (rank > best_rank) best = c, best_rank = rank, best_density = d.raw(c, rho);
        }
        const Rgb rgb = colour(best, best_density);
        for (int y = 0; y < scale; ++y)
          for (int x = 0; x < scale; ++x) image.set(col * scale + x, top + (v.height - 1 - row) * scale + y, rgb);
      }
    top += v.height * scale + gap;
  }
  image.write_png(path);
  return path;
}

}  // namespace msfab
