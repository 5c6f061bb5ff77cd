#pragma once
// Conjugate gradients preconditioned by one geometric multigrid V-cycle
// ("pcg-mg"), for stiffness matrices of voxel meshes: 3 unknowns per node,
// nodes on a regular lattice (given by LinearSolverOptions::node_positions).
//
// Hierarchy: level 0 is the mesh; level l+1 keeps the lattice points of
// level l with even coordinates that lie next to a node of level l.
// Trilinear prolongation per displacement component, Galerkin coarse
// operators P^T A P (pattern and index tables built in analyze(), values in
// factorize()), Chebyshev / block-Jacobi smoothing before and after each
// coarse correction, and CHOLMOD on the coarsest level. Every kernel is
// OpenMP-parallel and bitwise deterministic for any thread count.
#include <cstdint>
#include <memory>
#include <vector>

#include "solve/linear_solver.hpp"

namespace msfab {

class CholmodSolver;

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
  // One V-cycle, z = M^-1 r, after a successful factorize().
  VecX apply_preconditioner(const VecX& r);

 private:
  struct Level;
  void v_cycle(std::size_t level, const VecX& rhs, VecX& solution);

  LinearSolverOptions options_;
  LinearSolveStats stats_;
  std::vector<std::unique_ptr<Level>> levels_;
  SpMat coarsest_;  // the coarsest level's operator, as CHOLMOD reads it
  std::unique_ptr<CholmodSolver> coarse_solver_;
  Eigen::Index n_ = -1;  // -1: not analyzed
  std::uint64_t pattern_ = 0;
  bool ready_ = false;  // the last factorize() succeeded
};

}  // namespace msfab
