#include "solve/linear_solver.hpp"

#include "core/errors.hpp"
#include "solve/cholmod_solver.hpp"
#include "solve/multigrid_solver.hpp"
#include "solve/pcg_solver.hpp"

namespace msfab {

LinearSolver::~LinearSolver() = default;

void validate_linear_solver_options(const LinearSolverOptions& options) {
  if (!(options.pcg_tolerance > 0.0 && options.pcg_tolerance < 1.0)) {
    throw InputError("linear solver option pcg_tolerance must lie in (0, 1), got " +
                     std::to_string(options.pcg_tolerance));
  }
  if (options.pcg_max_iterations <= 0) {
    throw InputError("linear solver option pcg_max_iterations must be positive, got " +
                     std::to_string(options.pcg_max_iterations));
  }
  if (options.pcg_preconditioner != "jacobi" && options.pcg_preconditioner != "block-jacobi3") {
    throw InputError("linear solver option pcg_preconditioner is '" + options.pcg_preconditioner +
                     "'; valid: jacobi, block-jacobi3");
  }
  if (options.threads < 0) {
    throw InputError("linear solver option threads must be >= 0 (0: OpenMP default), got " +
                     std::to_string(options.threads));
  }
}

std::vector<std::string> linear_solver_names() { return {"cholmod", "pcg", "pcg-mg"}; }

std::unique_ptr<LinearSolver> make_linear_solver(const std::string& name, const LinearSolverOptions& options) {
  if (name == "cholmod") return std::make_unique<CholmodSolver>(options);
  if (name == "pcg") return std::make_unique<PcgSolver>(options);
  if (name == "pcg-mg") return std::make_unique<MultigridSolver>(options);
  std::string valid;
  for (const std::string& known : linear_solver_names()) {
    valid += (valid.empty() ? "" : ", ") + known;
  }
  throw InputError("linear solver '" + name + "' is unknown; valid names: " + valid);
}

}  // namespace msfab
