#pragma once
// What msfab-topopt writes: the `msfab.design` content of an optimization
// result (`python3 -m msfab report` draws its convergence and cells).
#include "topopt/design_artifact.hpp"
#include "topopt/topology_optimizers.hpp"

namespace msfab {

Design make_design(TopologyObjective& objective, const OptimizationResult& result, double E_stiff, double decades);

}  // namespace msfab
