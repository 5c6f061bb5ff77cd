#pragma once
// The optimizers of the topology stage (thesis §3.4, §3.6.2):
//
//  * optimize_in_gamut: Ipopt (interior point, limited-memory BFGS Hessian)
//    on problem 3.5: min S(p) over the unit parameters of the design cells,
//    s.t. Phi(p_i) <= 0 per cell (when the material space has a constraint)
//    and, optionally, a mass budget sum rho_i V_i <= M. Equilibrium enters
//    through the adjoint gradient of TopologyObjective.
//  * optimize_oc: the optimality-criteria update of the classic SIMP codes
//    (bisection on the volume multiplier, move limit, damping 1/2), for
//    single-parameter spaces with a volume budget: the baseline.
//  * optimize_mma (topopt/simp_mma.hpp): NLopt's MMA on the same problem.
//  * optimize_cell_mma (topopt/cell_mma.hpp): MMA whose subproblem
//    separates over the cells, for every space; the large problems.
#include <string>
#include <vector>

#include "topopt/topology_objective.hpp"

namespace msfab {

struct OptimizerSettings {
  int max_iterations = 100;
  double tolerance = 1e-5;             // Ipopt: relative convergence tolerance (on the scaled objective)
  double constraint_tolerance = 1e-3;  // Ipopt: Phi violation accepted at the end (normalized units)
  int lbfgs_memory = 8;
  bool mass_limit = false;  // add the constraint sum rho_i V_i <= mass_budget
  double mass_budget = 0;
  double oc_move = 0.2;   // OC only
  double mma_move = 0.2;  // cell MMA: largest step per iteration, in unit parameters
  // OC and MMA: stop when no design variable changes by this much in an
  // iteration (0: never; run max_iterations).
  double change_tolerance = 0.01;
  int log_every = 10;  // progress line every this many iterations (0: none)
};

struct OptimizationResult {
  MatX q;                // final design variables
  ObjectiveValue value;  // at q
  std::vector<DesignHistoryEntry> history;
  std::string status;  // optimizer's own words
  bool converged = false;
  int iterations = 0, evaluations = 0;
  double max_violation = 0;  // max_i of Phi(p_i) and the Voigt bound's conditions (or the mass excess) at q
  double seconds = 0;
  double update_seconds = 0;  // time outside the objective's evaluations (cell MMA: the subproblems)
};

OptimizationResult optimize_in_gamut(TopologyObjective& objective, const MatX& q0, const OptimizerSettings& settings);
// Requires a one-parameter space (simp*) and settings.mass_limit.
OptimizationResult optimize_oc(TopologyObjective& objective, const MatX& q0, const OptimizerSettings& settings);

// A cell's conditions at parameters p: Phi first, then the Voigt bound's
// (model.bound_conditions() of them); with `jacobian`, their gradients as
// rows. Empty for a model without a constraint.
VecX cell_gamut_conditions(const CellMaterialModel& model, const VecX& p, MatX* jacobian);

// Largest Phi, or Voigt-bound condition, over the design cells at filtered
// parameters p.
double max_gamut_violation(const CellMaterialModel& model, const MatX& p);

}  // namespace msfab
