#pragma once
// The method of moving asymptotes for the SIMP baselines (simp2d, simp3d):
// NLopt's LD_MMA (Svanberg's conservative convex separable approximations,
// the globally convergent form), min S(q) s.t. mass(q) <= mass budget,
// 0 <= q <= 1. The density filter lives inside the objective, so the
// volume constraint is linear in q (its gradient is the filter's column
// sums) and needs no FEM work.
//
// Iterations are objective evaluations: each costs one FEM solve, whether
// NLopt keeps the point as its next iterate or (an inner iteration of the
// globally convergent scheme) rejects it as not conservative enough.
// `max_iterations` design updates mean max_iterations + 1 evaluations, so
// history entry k is the design after k updates, as in optimize_oc.
#include "topopt/topology_optimizers.hpp"

namespace msfab {

// Requires a one-parameter (simp) space and settings.mass_limit
// (InputError otherwise). Stops after settings.max_iterations updates or
// when no design variable moves by settings.change_tolerance or more from
// one outer MMA iterate to the next (0 disables that test). The result and
// every history entry are MMA's iterate: the best feasible design
// evaluated so far (a rejected trial point leaves it unchanged). The
// history's max_violation is the volume excess over the budget as a
// fraction of the domain volume.
OptimizationResult optimize_mma(TopologyObjective& objective, const MatX& q0, const OptimizerSettings& settings);

}  // namespace msfab
