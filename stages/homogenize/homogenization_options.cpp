#include "homogenization_options.hpp"

#include "io/linear_solver_config.hpp"

namespace msfab {

HomogenizationOptions read_homogenization_options(const Config& config) {
  HomogenizationOptions options;
  options.void_stiffness = config.get_or<double>("void_stiffness", options.void_stiffness);
  if (!(options.void_stiffness > 0 && options.void_stiffness < 1e-2))
    config.fail("void_stiffness", "must be in (0, 0.01)");
  LinearSolverChoice defaults;
  defaults.kind = options.solver;
  defaults.tolerance = options.tolerance;
  defaults.max_iterations = options.max_iterations;
  LinearSolverKeys keys;
  keys.legacy_kind = "solver";
  keys.legacy_tolerance = "multigrid_tolerance";
  const LinearSolverChoice linear =
      read_linear_solver_choice(config, {"auto", "cholmod", "matrix-free"}, defaults, keys);
  options.solver = linear.kind;
  options.tolerance = linear.tolerance;
  options.max_iterations = linear.max_iterations;
  options.max_iterations_key = linear.max_iterations_key;
  // Both exact reductions (two strain cases for a cubic cell, one octant
  // for a mirror-symmetric one); false solves six cases on the whole cell.
  options.use_symmetry = options.use_mirror_symmetry = config.get_or<bool>("use_symmetry", true);
  return options;
}

}  // namespace msfab
