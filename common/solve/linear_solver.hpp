#pragma once
// Sparse symmetric linear solvers behind one interface, so the Newton solver
// can switch between a direct factorization and an iterative method by name.
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace msfab {

struct LinearSolverOptions {
  // PCG stops when ||b - (A + shift I) x|| <= pcg_tolerance * ||b||.
  double pcg_tolerance = 1e-8;
  int pcg_max_iterations = 10000;
  // The config key pcg_max_iterations was read from, for messages (empty:
  // not configurable where this solver runs).
  std::string pcg_max_iterations_key;
  // "jacobi" (diagonal) or "block-jacobi3" (3x3 diagonal blocks, one per
  // mesh node with 3 displacement unknowns; needs n divisible by 3).
  std::string pcg_preconditioner = "jacobi";
  // OpenMP threads for the parallel kernels; 0 uses the OpenMP default.
  // CHOLMOD also sets the (process-wide) OpenBLAS thread count to this when
  // it is > 0; with 0 the BLAS follows OPENBLAS_NUM_THREADS.
  int threads = 0;

  // pcg-mg (multigrid-preconditioned CG; also uses pcg_tolerance and
  // pcg_max_iterations): the rest positions of the mesh nodes, one row per
  // node in DOF order (a NodeArray of fem/hex_mesh.hpp). They must lie on a
  // regular lattice, as the nodes of a voxel mesh do.
  std::shared_ptr<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>> node_positions;
  // pcg-mg: coarsening stops at the first level with fewer unknowns than
  // this; CHOLMOD factors that level.
  int mg_coarse_unknowns = 3000;
  // pcg-mg: degree of the Chebyshev smoother, applied before and after each
  // coarse correction (matrix products per smoothing).
  int mg_smoother_degree = 2;
  // cholmod: factor symmetric indefinite matrices as L D L^T (simplicial,
  // without pivoting: about the fill of L L^T, with slower kernels).
  // factorize() then fails only on a zero pivot, and the factor's negative
  // pivots count the matrix's negative eigenvalues (Sylvester's law of
  // inertia). Where no negative pivot is expected the L L^T default is
  // faster.
  bool indefinite = false;
};

struct LinearSolveStats {
  int iterations = 0;              // CG iterations of the last solve (0 for direct)
  double relative_residual = 0.0;  // ||b - (A + shift I) x|| / ||b|| of the last solve
  double analyze_seconds = 0.0;    // last analyze()
  double factorize_seconds = 0.0;  // last factorize()
  double solve_seconds = 0.0;      // last solve()
  bool positive_definite = false;  // last factorize() (PCG: also its last solve)
};

// Usage: analyze(A) once per sparsity pattern, factorize(A, shift) whenever
// the values change, solve(b) for each right-hand side.
//
// A is symmetric and given with both triangles. The solver keeps a reference
// to the matrix passed to factorize() (to compute residuals, and for PCG to
// multiply by it), so that matrix must stay alive and unchanged until the
// last solve() that follows.
class LinearSolver {
 public:
  virtual ~LinearSolver();

  // Pattern-dependent work (ordering, symbolic factorization).
  virtual void analyze(const SpMat& A) = 0;
  // Prepares solves with A + shift*I (the shift regularizes an indefinite
  // Hessian). Returns false if that matrix is found not positive definite;
  // solve() then throws until a later factorize() succeeds. A must have the
  // pattern given to analyze().
  virtual bool factorize(const SpMat& A, double shift = 0.0) = 0;
  // Solves (A + shift I) x = b. Throws NumericalError on failure.
  virtual VecX solve(const VecX& b) = 0;

  virtual const LinearSolveStats& stats() const = 0;
  virtual std::string name() const = 0;
};

// Throws InputError naming the first invalid field.
void validate_linear_solver_options(const LinearSolverOptions& options);

// The names make_linear_solver() accepts.
std::vector<std::string> linear_solver_names();

// name: "cholmod" | "pcg" | "pcg-mg". Throws InputError for an unknown name or an
// invalid option, naming the field and the valid choices.
std::unique_ptr<LinearSolver> make_linear_solver(const std::string& name, const LinearSolverOptions& options = {});

}  // namespace msfab
