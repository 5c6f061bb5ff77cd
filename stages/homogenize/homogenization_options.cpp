#include "homogenization_options.hpp"

namespace msfab {

HomogenizationOptions read_homogenization_options(const Config& config) {
  HomogenizationOptions options;
  options.void_stiffness = config.get_or<double>("void_stiffness", options.void_stiffness);
  if (!(options.void_stiffness > 0 && options.void_stiffness < 1e-2)) config.fail("void_stiffness", "must be in (0, 0.01)");
  if (config.has("solver")) options.solver = config.one_of("solver", {"auto", "direct", "multigrid"});
  options.multigrid_tolerance = config.get_or<double>("multigrid_tolerance", options.multigrid_tolerance);
  if (!(options.multigrid_tolerance > 0 && options.multigrid_tolerance < 1))
    config.fail("multigrid_tolerance", "must be in (0, 1)");
  // Both exact reductions (two strain cases for a cubic cell, one octant
  // for a mirror-symmetric one); false solves six cases on the whole cell.
  options.use_symmetry = options.use_mirror_symmetry = config.get_or<bool>("use_symmetry", true);
  return options;
}

}  // namespace msfab
