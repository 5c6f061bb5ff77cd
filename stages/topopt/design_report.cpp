#include "design_report.hpp"

#include <algorithm>
#include <cmath>

#include "io/chart.hpp"

namespace msfab {

Design make_design(TopologyObjective& objective, const OptimizationResult& r, double E_stiff, double decades) {
  const CellGrid& g = objective.grid();
  const CellMaterialModel& model = objective.model();
  Design d;
  d.space = model.space();
  d.property_names = model.names();
  d.E_stiff = E_stiff;
  d.decades = decades;
  d.dimension = g.dimension();
  d.nx = g.nx(), d.ny = g.ny(), d.nz = g.nz();
  d.cell_size = g.h();
  d.roles = objective.setup().roles;
  const int n = model.parameters();
  d.unit = MatX::Zero(g.cells(), n);
  d.raw = MatX::Zero(g.cells(), n);
  d.phi = VecX::Zero(g.cells());
  for (std::int64_t c = 0; c < g.cells(); ++c)
    if (d.roles[c] == CellRole::solid) d.unit(c, n - 1) = d.raw(c, n - 1) = 1.0;
  const MatX p = objective.physical(r.q);
  for (std::size_t i = 0; i < objective.design_cells().size(); ++i) {
    const std::int64_t c = objective.design_cells()[i];
    const VecX pc = p.row(Eigen::Index(i)).transpose();
    d.unit.row(c) = pc.transpose();
    d.raw.row(c) = model.raw(pc).transpose();
    d.phi[c] = model.constraint(pc, nullptr);
  }
  objective.evaluate(r.q, nullptr);
  const VecX& u = objective.displacements().front();
  d.displacement = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      u.data(), g.nodes(), g.dimension());
  d.history = r.history;
  return d;
}

std::string write_convergence_plot(const std::string& artifact, const OptimizationResult& r, const std::string& space) {
  std::string stem = artifact;
  if (stem.size() > 3 && stem.compare(stem.size() - 3, 3, ".h5") == 0) stem.resize(stem.size() - 3);
  if (stem.size() > 7 && stem.compare(stem.size() - 7, 7, ".design") == 0) stem.resize(stem.size() - 7);
  const std::string path = stem + ".convergence.png";
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
