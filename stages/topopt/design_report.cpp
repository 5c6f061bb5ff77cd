#include "design_report.hpp"

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

}  // namespace msfab
