#pragma once
// Nonlinear elastostatics by Newton's method with backtracking line search
// (thesis Algorithm 1), with load stepping for large loads.
//
// Unknowns are node positions. Dirichlet DOFs are driven to their
// prescribed values through the Newton step itself (the gap between the
// current and the prescribed position is part of the step), so a large
// prescribed displacement moves the interior along with the boundary
// instead of inverting the elements next to it.
#include <functional>
#include <string>
#include <vector>

#include "fem/elastic_assembler.hpp"
#include "solve/linear_solver.hpp"

namespace msfab {

struct DirichletConditions {
  std::vector<char> fixed;  // per DOF: 1 if prescribed
  VecX displacement;        // per DOF: displacement at full load (read where fixed)

  static DirichletConditions none(int num_dofs) { return {std::vector<char>(num_dofs, 0), VecX::Zero(num_dofs)}; }
  int count_fixed() const;
};

struct NewtonIteration;

struct NewtonOptions {
  double relative_tolerance = 1e-6;  // on ||residual|| / force scale
  int max_iterations = 50;           // per load step
  int load_steps = 1;                // initial number of equal load increments
  int max_step_halvings = 8;         // adaptive cuts of a failing increment
  double armijo = 1e-4;
  int max_line_search = 40;
  // "auto" picks CHOLMOD below auto_iterative_dofs unknowns and
  // multigrid-preconditioned CG (pcg-mg) above; or name a solver.
  std::string linear_solver = "auto";
  int auto_iterative_dofs = 4000;  // measured crossover, docs/solvers.md
  // newton_step_from at an indefinite tangent: the most unknowns it factors
  // directly (CHOLMOD; about 70 k elements of a 3D mesh, a factor of about
  // 3 GB). With pcg-mg it first runs MINRES preconditioned by the multigrid
  // and factors only where that fails.
  int largest_indefinite_direct_step = 200000;
  LinearSolverOptions linear;
  // Called after each converged load increment with the load factor reached.
  std::function<void(double load_factor)> on_load_step;
  // Called with each Newton iteration's record as it is added to the
  // history (progress within a load increment).
  std::function<void(const NewtonIteration&)> on_iteration;
};

struct NewtonIteration {
  int load_step = 0;
  double load_factor = 0;
  int iteration = 0;
  double residual = 0;     // ||free residual|| / force scale
  double energy = 0;       // total potential
  double step_length = 0;  // accepted line-search step
  double shift = 0;        // diagonal regularization used (0 if none)
  int linear_iterations = 0;
};

struct NewtonTimings {
  double assembly = 0;     // energy, gradient, Hessian (Alg. 1 lines 2-18)
  double solve = 0;        // factorization and solve (line 19)
  double line_search = 0;  // lines 20-21
  double total = 0;
};

struct NewtonResult {
  VecX x;  // final positions
  bool converged = false;
  int iterations = 0;
  int load_steps = 0;
  std::vector<NewtonIteration> history;
  NewtonTimings timings;
  std::string failure;  // why it stopped, when not converged
};

// Solves for equilibrium under external nodal forces `force` (full load)
// and `dirichlet`. Starts from x0 (rest positions if empty). Never throws
// on non-convergence: the result says converged = false with the reason
// and the residual history, and callers decide (stages exit with code 3).
NewtonResult solve_static(const ElasticAssembler& assembler, const DirichletConditions& dirichlet, const VecX& force,
                          const NewtonOptions& options, const VecX& x0 = VecX());

// One full Newton step of the problem at full load from the positions x,
// without line search, fixed DOFs moved onto their prescribed values. Near
// this model's solution u* the step is u* - x up to terms of second order in
// |u* - x|, so its size estimates how far an approximate solution (e.g. one
// of a coarser model) lies from this model's own, errors of every origin
// included. The step is the exact one whether or not it descends: where
// the tangent at x is not positive definite (`indefinite`), it is solved by
// MINRES preconditioned with a shifted CHOLMOD factor (L D L^T where MINRES
// stalls), up to 200 000 unknowns. On larger meshes such a tangent is
// regularized as solve_static's steps are (a shift of the diagonal, growing
// until the step descends) and `shift` says by how much.
// Where there is no step at all, `failure` says why (an inverted element at
// x, a singular tangent, a system that no shift made solvable) and `step`
// is empty.
struct NewtonStepFrom {
  VecX step;
  std::string failure;
  double shift = 0;         // the regularization the step needed (0: none)
  bool indefinite = false;  // the tangent at x is not positive definite (and the step is still exact)
};
NewtonStepFrom newton_step_from(const ElasticAssembler& assembler, const DirichletConditions& dirichlet,
                                const VecX& force, const NewtonOptions& options, const VecX& x);
// The linear solver solve_static runs for `dofs` unknowns: options'
// linear_solver with "auto" resolved by auto_iterative_dofs.
std::string static_linear_solver(double dofs, const NewtonOptions& options);

// Peak memory of solve_static on a hexahedral mesh of `elements` elements
// and `dofs` unknowns, from /usr/bin/time on cubes of 24^3 to 64^3 voxels
// (docs/cli.md, "Memory"): about 10 kB per element for the assembled
// matrix, its multigrid hierarchy and Newton's vectors, and for CHOLMOD
// the factor's nested-dissection fill, about 1 kB x elements^(4/3).
double static_solve_peak_bytes(double elements, double dofs, const NewtonOptions& options);

// Zeroes the rows and columns of fixed DOFs and puts `diag` on their
// diagonal, so the system decouples into the free block and an identity-like
// block whose solution is the prescribed gap.
void constrain_matrix(SpMat& K, const std::vector<char>& fixed, double diag);

// The residual history as readable text, for error messages.
std::string format_history(const std::vector<NewtonIteration>& history, size_t max_lines = 30);

}  // namespace msfab
