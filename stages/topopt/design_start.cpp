#include "design_start.hpp"

#include <algorithm>

#include "core/errors.hpp"

namespace msfab {

MatX DesignStart::rows(const std::vector<std::int64_t>& design_cells) const {
  MatX q(Eigen::Index(design_cells.size()), per_cell.cols());
  for (std::size_t r = 0; r < design_cells.size(); ++r) q.row(Eigen::Index(r)) = per_cell.row(design_cells[r]);
  return q;
}

DesignStart read_design_start(const Config& config, const CellMaterialModel& model, const CellGrid& grid) {
  DesignStart start;
  start.per_cell.resize(grid.cells(), model.parameters());
  if (config.has("initial.design")) {
    if (config.has("initial.rho")) config.fail("initial.rho", "give either initial.rho or initial.design");
    start.path = config.get_path("initial.design");
    const Design coarse = read_design_artifact(start.path);
    const std::vector<std::string> family = model.family_names();
    if (coarse.space != model.design_space() || coarse.family_names != family)
      config.fail("initial.design", start.path + " is a design in space " + coarse.space +
                                        (coarse.family_names.empty() ? "" : " (a family's parameters)") +
                                        ", this run uses " + model.space());
    if (coarse.dimension != grid.dimension())
      config.fail("initial.design", start.path + " is " + std::to_string(coarse.dimension) + "D");
    for (std::int64_t c = 0; c < grid.cells(); ++c) {
      const auto [i, j, k] = grid.cell_coords(c);
      const int ci = std::min(coarse.nx - 1, int((i + 0.5) * coarse.nx / grid.nx()));
      const int cj = std::min(coarse.ny - 1, int((j + 0.5) * coarse.ny / grid.ny()));
      const int ck = std::min(coarse.nz - 1, int((k + 0.5) * coarse.nz / grid.nz()));
      const std::int64_t cc = ci + std::int64_t(coarse.nx) * (cj + std::int64_t(coarse.ny) * ck);
      if (family.empty()) {
        start.per_cell.row(c) = model.parameters_of_design_unit(coarse.unit.row(cc).transpose()).transpose();
      } else {  // the family's parameters, then rho
        const Eigen::Index k = Eigen::Index(family.size());
        start.per_cell.row(c).head(k) = coarse.family_unit.row(cc);
        start.per_cell(c, k) = coarse.unit(cc, coarse.unit.cols() - 1);
      }
      // A coarse cell outside its design domain has no parameters to give.
      if (coarse.roles[cc] != CellRole::design)
        start.per_cell.row(c) = model.initial_point(coarse.roles[cc] == CellRole::solid ? 0.9 : 0.1).transpose();
    }
    return start;
  }
  const double rho = config.get_or<double>("initial.rho", 0.5);
  if (!(rho > 0 && rho < 1)) config.fail("initial.rho", "must be in (0, 1)");
  const VecX p = model.initial_point(rho);
  for (std::int64_t c = 0; c < grid.cells(); ++c) start.per_cell.row(c) = p.transpose();
  return start;
}

}  // namespace msfab
