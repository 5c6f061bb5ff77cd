#pragma once
// What msfab-topopt writes: the `msfab.design` content of an optimization
// result, and its convergence plot.
#include <string>

#include "topopt/design_artifact.hpp"
#include "topopt/topology_optimizers.hpp"

namespace msfab {

Design make_design(TopologyObjective& objective, const OptimizationResult& result, double E_stiff, double decades);
// "<stem>.convergence.png" next to the artifact: elastic objective and
// constraint violation against the iteration. Returns its path.
std::string write_convergence_plot(const std::string& artifact, const OptimizationResult& result,
                                   const std::string& space);

// "<stem>.density.png": the cells' density, black = solid, white = void
// (forced-solid cells blue, forced-empty cells pale red). A 2D design is
// drawn as is (y up); a 3D design as two views, one above the other: the
// largest density along y (front, z up) and along z (top, y up).
// Returns its path.
std::string write_density_picture(const std::string& artifact, const Design& design);

}  // namespace msfab
