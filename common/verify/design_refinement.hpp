#pragma once
// The elasticity of a two-scale design on m^3 hexahedra per design cell
// (config `elements_per_cell`): the design grid's supports, prescribed
// values, forces and targets carried to the finer mesh by the rules the
// full-resolution check uses for its homogenized model
// (verify/refinement.hpp), so that a design optimized with m elements per
// cell is the model `msfab-verify-map --set homogenized_elements=m` checks.
#include "topopt/topology_objective.hpp"

namespace msfab {

// Refines `setup` (fixed flags and load vectors on setup.grid) in place to
// m^3 hexahedra per cell; m = 1 leaves it as it is. Targets stay at the
// design grid's nodes (the fine nodes that coincide with them).
void refine_fem_mesh(TopologySetup& setup, int m);

}  // namespace msfab
