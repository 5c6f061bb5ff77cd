#include "dynamics/dac_coarsening.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/errors.hpp"

namespace msfab {

namespace {

void check_options(const DacOptions& o) {
  auto bad = [](const std::string& what) { throw InputError("DAC coarsening options: " + what); };
  if (o.max_level < o.first_level) bad("max_level must be >= first_level");
  if (o.num_modes < 1) bad("num_modes must be at least 1");
  if (!(o.convergence_tolerance > 0)) bad("convergence_tolerance must be positive");
  if (!(o.shape_tolerance > 0)) bad("shape_tolerance must be positive");
  if (o.match_window < 0) bad("match_window must be >= 0");
}

}  // namespace

DacResult dac_geometric_coarsening(const DacLevelBuilder& build, const DacOptions& options) {
  check_options(options);
  ModalOptions modal = options.modal;
  modal.num_modes = options.num_modes + options.match_window;
  modal.skip_rigid = true;
  const int k = options.num_modes;

  DacResult result;
  std::vector<ModeShapeSurface> surfaces;
  std::vector<ModalResult> modes;
  for (int level = options.first_level; level <= options.max_level; ++level) {
    DacLevel built = build(level);
    DacLevelReport report;
    report.level = level;
    report.elements = built.mesh.num_elements();
    report.dofs = built.mesh.num_dofs();
    report.element_size = built.element_size;
    modes.push_back(modal_analysis(built.mesh, built.density, built.fixed, modal));
    surfaces.push_back(mode_shape_surface(built.mesh));
    report.frequencies = modes.back().frequencies;
    if (!result.levels.empty()) {
      const VecX& previous = result.levels.back().frequencies;
      for (int i = 0; i < k; ++i)
        report.frequency_change = std::max(
            report.frequency_change, std::abs(report.frequencies(i) - previous(i)) / report.frequencies(i));
    }
    result.levels.push_back(std::move(report));
    if (result.levels.size() > 1 && result.levels.back().frequency_change < options.convergence_tolerance) {
      result.converged = true;
      break;
    }
  }
  const size_t reference = result.levels.size() - 1;
  result.convergent_level = result.levels[reference].level;

  bool chosen = false;
  for (size_t l = 0; l < result.levels.size(); ++l) {
    DacLevelReport& report = result.levels[l];
    report.matches = match_modes(surfaces[reference], modes[reference].modes, surfaces[l],
                                 modes[l].modes.leftCols(k), options.match_window, options.distance);
    report.max_distance = 0;
    for (const ModeMatch& m : report.matches) report.max_distance = std::max(report.max_distance, m.distance);
    report.within_tolerance = report.max_distance <= options.shape_tolerance;
    if (report.within_tolerance && !chosen) {
      chosen = true;
      result.chosen_index = l;
      result.chosen_level = report.level;
    }
  }
  // The reference matches itself at distance 0, so a level is always chosen.
  result.chosen_modes = modes[result.chosen_index];
  result.convergent_modes = modes[reference];
  return result;
}

}  // namespace msfab
