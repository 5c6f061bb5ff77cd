#include "static_solve.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "cli/progress.hpp"
#include "core/errors.hpp"

namespace msfab {

NewtonResult solve_or_throw(const ElasticAssembler& assembler, const StaticConditions& conditions,
                            const NewtonOptions& options, const char* label, const VecX& x0) {
  NewtonOptions newton = options;
  Progress progress(label, 100);
  // Percent of the load, moving within an increment too: the share of the
  // residual's way (in decades) from its largest value in the increment to
  // the tolerance, so that a long increment does not sit at one number for
  // minutes. (With prescribed displacements the first residual of an
  // increment is small: the gap, not the residual, is what is open.)
  double converged_load = 0, largest_residual = 0;
  std::uint64_t shown = 0;
  const auto show = [&](double load) {
    shown = std::max(shown, static_cast<std::uint64_t>(100 * std::min(load, 1.0) + 0.5));
    progress.set(shown);
  };
  newton.on_load_step = [&](double load) {
    converged_load = load;
    show(load);
  };
  newton.on_iteration = [&](const NewtonIteration& it) {
    largest_residual = it.iteration == 0 ? it.residual : std::max(largest_residual, it.residual);
    const double tolerance = options.relative_tolerance;
    double done = 0;
    if (largest_residual > tolerance && it.residual > 0)
      done = std::log(largest_residual / std::max(it.residual, tolerance)) / std::log(largest_residual / tolerance);
    show(converged_load + (it.load_factor - converged_load) * std::clamp(done, 0.0, 0.95));
  };
  NewtonResult result = solve_static(assembler, conditions.dirichlet, conditions.force, newton, x0);
  progress.done();
  if (!result.converged)
    throw NumericalError(std::string(label) + ": " + result.failure + "\nresidual history:\n" +
                         format_history(result.history));
  return result;
}

}  // namespace msfab
