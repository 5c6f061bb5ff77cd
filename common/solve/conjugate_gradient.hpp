#pragma once
// The preconditioned conjugate-gradient loop shared by the iterative linear
// solvers ("pcg" and "pcg-mg"). The solvers supply the operator A + shift I
// and the preconditioner M^-1 as callbacks; this loop owns the stopping
// rule, the true-residual restart, the failure messages and the stats.
#include <functional>
#include <string>

#include "core/types.hpp"
#include "solve/linear_solver.hpp"

namespace msfab {

// The operator A + shift I (symmetric positive definite).
struct CgOperator {
  // y = (A + shift I) x; resizes y.
  std::function<void(const VecX& x, VecX& y)> multiply;
  // The same product, returning x . y (the curvature CG needs).
  std::function<double(const VecX& x, VecX& y)> multiply_dot;
};

// The preconditioner M^-1 (symmetric positive definite).
struct CgPreconditioner {
  // z = M^-1 r; resizes z and returns r . z.
  std::function<double(const VecX& r, VecX& z)> apply;
  // Optional: z = M^-1 r on entries [begin, end) only, returning their part
  // of r . z. Given for a preconditioner that acts on each reduction chunk
  // of solve/sparse_ops.hpp on its own (e.g. (block) Jacobi): CG then fuses
  // it into the pass that updates x and r, reading the memory once.
  std::function<double(const double* r, double* z, Eigen::Index begin, Eigen::Index end)> apply_chunk;
  // Throw NumericalError unless r . M^-1 r > 0 after each application; for
  // a preconditioner whose definiteness is not guaranteed by its setup.
  bool check_definite = false;
};

struct CgSettings {
  double tolerance = 1e-8;  // stop when ||b - (A + shift I) x|| <= tolerance ||b||
  int max_iterations = 10000;
  // The config key that sets max_iterations, named when it is reached
  // (empty: an internal limit, no key to raise).
  std::string max_iterations_key;
  int threads = 0;  // as in LinearSolverOptions::threads
  // Names the method in messages: "<label> did not converge: ...".
  std::string label;
  // Names the method in "<curvature_label> met non-positive curvature ...".
  std::string curvature_label;
  // Whether that message also gives the relative residual reached so far.
  bool curvature_message_has_residual = false;
  // Called every progress_stride iterations with the relative residual of
  // the recursion (long solves report where they are; none when empty).
  std::function<void(int iteration, double relative_residual)> progress;
  int progress_stride = 50;
};

// Solves (A + shift I) x = b by preconditioned CG from x = 0, with results
// bitwise independent of the thread count when the callbacks are. Sets
// stats.iterations, relative_residual and solve_seconds. Throws
// NumericalError if max_iterations pass before the tolerance is reached
// (listing the relative residual every max_iterations / 8 iterations), or on
// non-positive curvature or r . M^-1 r (then stats.positive_definite is
// false).
// CG around a multigrid cycle, as the multigrid solvers run it: the
// operator's product with x . y taken after it, the cycle as the
// preconditioner, checked for definiteness after each application (a cycle
// whose coarse operators lost definiteness shows up there first), and
// settings whose messages name `label`. Callers add what is their own (a
// fused product, a progress hook, the config key of the limit). An empty
// `multiply` leaves the operator empty.
struct CgSetup {
  CgOperator op;
  CgPreconditioner preconditioner;
  CgSettings settings;
};
CgSetup multigrid_cg_setup(std::function<void(const VecX& x, VecX& y)> multiply,
                           std::function<void(const VecX& r, VecX& z)> cycle, double tolerance, int max_iterations,
                           int threads, const std::string& label);

// The CG stopping rule and thread count, copied between option structs that
// name them alike (tolerance, max_iterations, max_iterations_key, threads):
// the homogenization's, the octant solver's and the grid multigrids'.
template <class To, class From>
void copy_cg_limits(const From& from, To& to) {
  to.tolerance = from.tolerance;
  to.max_iterations = from.max_iterations;
  to.max_iterations_key = from.max_iterations_key;
  to.threads = from.threads;
}

VecX conjugate_gradient(const CgOperator& A, const CgPreconditioner& M, const VecX& b, const CgSettings& settings,
                        LinearSolveStats& stats);

}  // namespace msfab
