#pragma once
// Conjugate gradients preconditioned by one geometric multigrid cycle
// ("pcg-mg"), for stiffness matrices of voxel meshes: 3 unknowns per node,
// nodes on a regular lattice (given by LinearSolverOptions::node_positions).
//
// Hierarchy: level 0 is the mesh; level l+1 keeps the lattice points of
// level l with even coordinates that lie next to a node of level l.
// Trilinear prolongation per displacement component, Galerkin coarse
// operators P^T A P (pattern and index tables built in analyze(), values in
// factorize()), Chebyshev / block-Jacobi smoothing before and after each
// coarse correction (one correction on the finest level, two on each level
// below: a V-cycle on top of W-cycles), and a sparse Cholesky factorization
// of the coarsest level. The cycle is a fixed symmetric positive definite
// operator, so plain CG applies. Every kernel is OpenMP-parallel and
// bitwise deterministic for any thread count.
#include <Eigen/SparseCholesky>
#include <cstdint>
#include <memory>
#include <vector>

#include "solve/linear_solver.hpp"

namespace msfab {

class MultigridSolver final : public LinearSolver {
 public:
  // Throws InputError for an invalid option.
  explicit MultigridSolver(const LinearSolverOptions& options = {});
  ~MultigridSolver() override;
  MultigridSolver(const MultigridSolver&) = delete;
  MultigridSolver& operator=(const MultigridSolver&) = delete;

  // Builds the hierarchy. Throws InputError ("pcg-mg needs a voxel mesh:
  // ...") without node positions, if they are not on a regular lattice, do
  // not match the matrix size, or the matrix couples non-neighbour nodes.
  void analyze(const SpMat& A) override;
  // Galerkin operators of A + shift I and smoother setup. Returns false if a
  // diagonal node block of some level, or the coarsest matrix, is not
  // positive definite.
  bool factorize(const SpMat& A, double shift = 0.0) override;
  // CG from x = 0 until ||b - (A + shift I) x|| <= pcg_tolerance ||b||.
  // Throws NumericalError if pcg_max_iterations pass first, or on
  // non-positive curvature (then stats().positive_definite is false).
  VecX solve(const VecX& b) override;
  const LinearSolveStats& stats() const override { return stats_; }
  std::string name() const override { return "pcg-mg"; }

  // Inspection, valid after analyze() (operators and P: after factorize()).
  int num_levels() const { return static_cast<int>(levels_.size()); }
  Eigen::Index level_unknowns(int level) const;
  // The operator of a level; level 0 is A + shift I.
  SpMat level_operator(int level) const;
  // Prolongation from level + 1 to level.
  SpMat prolongation(int level) const;
  // One multigrid cycle, z = M^-1 r, after a successful factorize().
  VecX apply_preconditioner(const VecX& r);

 private:
  struct Level;
  void cycle(std::size_t level, const VecX& rhs, VecX& solution);

  LinearSolverOptions options_;
  LinearSolveStats stats_;
  std::vector<std::unique_ptr<Level>> levels_;
  SpMat coarsest_;  // the coarsest level's operator in compressed columns
  // The coarsest level has a few thousand unknowns at most. A simplicial
  // factorization calls no BLAS: a supernodal one (CHOLMOD) would start the
  // multithreaded BLAS on every coarse solve, a large overhead at this size,
  // and its last bits would depend on the BLAS thread count.
  Eigen::SimplicialLLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>> coarse_solver_;
  Eigen::Index n_ = -1;  // -1: not analyzed
  std::uint64_t pattern_ = 0;
  bool ready_ = false;  // the last factorize() succeeded
};

}  // namespace msfab
