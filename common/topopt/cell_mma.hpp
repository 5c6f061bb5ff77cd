#pragma once
// The method of moving asymptotes with a subproblem that separates over the
// design cells: the optimizer for two-scale problems too large for Ipopt
// (thesis §3.4, Table 3.2: 10^5-10^6 cells).
//
// Problem 3.5 has a few constraints per cell (Phi and the Voigt bound's
// conditions) and at most one over the whole design (the mass budget).
// Ipopt treats them as one sparse system and factorizes its KKT matrix
// every iteration; at 37k cells that costs more than the FEM solve. Here
// every iteration builds MMA's convex separable approximations of the
// objective and of every constraint around the iterate, and the subproblem
// splits: per cell, a dual over that cell's multipliers
// (topopt/cell_mma_subproblem.hpp); over the design, a Newton search on the
// budget's multiplier. An iteration costs one objective evaluation (one FEM
// solve per load case and the adjoint gradient) plus work linear in the
// number of cells, spread over threads cell by cell, with the same result
// for any thread count.
//
// Regularization is the thesis's (§3.4: "a smoothing kernel on the
// gradient"): the variables are the cells' physical parameters, so the
// constraints stay per cell, and the gradient is smoothed with the cone
// weights of the density filter before the approximations are built.
// Where a space has no per-cell constraints (simp; family3d with rho
// derived from the family) the objective may carry a density filter
// instead: MMA's approximations of the objective and of the mass are
// separable in the variables whatever cells they reach through the filter,
// and the gradient is then exact. A smoothed gradient regularizes the
// steps, not the design: nothing stops two stiff cells from meeting at an
// edge only, which a model with a few hexahedra per cell holds far
// stiffer than the printed joint (docs/topopt.md, "Edge joints").
//
// Stopping: no variable moves by more than settings.change_tolerance in an
// iteration, or the objective changed by less than 1e-4 (relative) over
// the last 5 iterations with every constraint met to
// settings.constraint_tolerance; otherwise settings.max_iterations updates.
#include "topopt/cell_filter.hpp"
#include "topopt/topology_optimizers.hpp"

namespace msfab {

// x0: the cells' starting parameters (clamped into the box). InputError if
// the objective has a density filter and the space per-cell constraints,
// if both a density filter and gradient smoothing are given, or for a move
// limit outside (0, 1].
OptimizationResult optimize_cell_mma(TopologyObjective& objective, const MatX& x0, const OptimizerSettings& settings,
                                     const CellFilter& gradient_smoothing);

}  // namespace msfab
