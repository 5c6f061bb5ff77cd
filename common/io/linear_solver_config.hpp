#pragma once
// The linear solver a config chooses, in one vocabulary for every stage
// (docs/solvers.md, "Choosing a linear solver"):
//
//   linear_solver:          auto | cholmod | pcg | pcg-mg | matrix-free
//   linear_tolerance:       relative residual at which an iterative solve stops
//   linear_max_iterations:  CG iterations after which an iterative solve fails
//
// Each stage offers the kinds its problems can use, keeps its own defaults
// and resolves `auto` by its own measured rule (written beside its solver);
// what the keys mean is the same everywhere. The names used before this
// vocabulary (solver, pcg_tolerance, multigrid_tolerance, direct, multigrid,
// ...) are still read, with a warning naming the key to write instead.
#include <string>
#include <vector>

#include "io/config.hpp"

namespace msfab {

// Every kind of linear solver, in the order messages list them.
//   cholmod      sparse Cholesky factorization (CHOLMOD)
//   pcg          CG on the assembled matrix, Jacobi or block-Jacobi preconditioned
//   pcg-mg       CG on the assembled matrix, geometric multigrid preconditioned
//   matrix-free  CG with geometric multigrid on the voxel grid, no assembled matrix
//   auto         the stage's rule, by problem size
std::vector<std::string> linear_solver_kinds();

struct LinearSolverChoice {
  std::string kind = "auto";
  double tolerance = 1e-8;
  int max_iterations = 10000;
  // Full config paths the three values were read from, for messages
  // ("solver.linear_max_iterations").
  std::string kind_key, tolerance_key, max_iterations_key;
};

// Key names under the mapping a stage keeps its solver settings in; a stage
// with two solves (verify-map) prefixes the second one's.
struct LinearSolverKeys {
  std::string kind = "linear_solver";
  std::string tolerance = "linear_tolerance";
  std::string max_iterations = "linear_max_iterations";
  // Earlier names of the same keys (empty: none), read with a warning.
  std::string legacy_kind, legacy_tolerance, legacy_max_iterations;
};

// Reads the choice from `config`; absent keys keep `defaults`. The kind must
// be one of `offered` (a subset of linear_solver_kinds()); the legacy values
// "direct" and "multigrid" read as cholmod and matrix-free. InputError
// naming the key on anything else, a tolerance outside (0, 1) or an
// iteration limit below 1; a key given under both its names is an error.
LinearSolverChoice read_linear_solver_choice(const Config& config, const std::vector<std::string>& offered,
                                             const LinearSolverChoice& defaults, const LinearSolverKeys& keys = {});

// Between a choice and a solver's options, which name the limits
// pcg_tolerance, pcg_max_iterations and pcg_max_iterations_key
// (LinearSolverOptions; a template because solve/ sits beside io/, not
// below it).
template <class SolverOptions>
LinearSolverChoice linear_solver_defaults(const std::string& kind, const SolverOptions& options) {
  LinearSolverChoice defaults;
  defaults.kind = kind;
  defaults.tolerance = options.pcg_tolerance;
  defaults.max_iterations = options.pcg_max_iterations;
  return defaults;
}
template <class SolverOptions>
void apply_linear_solver_limits(const LinearSolverChoice& choice, SolverOptions& options) {
  options.pcg_tolerance = choice.tolerance;
  options.pcg_max_iterations = choice.max_iterations;
  options.pcg_max_iterations_key = choice.max_iterations_key;
}

// The choice with its kind replaced by a command-line option (--solver);
// the same checks, the message naming the option.
void override_linear_solver_kind(LinearSolverChoice& choice, const std::string& kind,
                                 const std::vector<std::string>& offered, const std::string& option_name);

}  // namespace msfab
