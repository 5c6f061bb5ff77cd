#pragma once
// Preconditioned conjugate gradients with a Jacobi or 3x3 block-Jacobi
// preconditioner. Every kernel is OpenMP-parallel with deterministic
// reductions (solve/sparse_ops.hpp), so results are bitwise identical for
// any thread count.
#include <cstdint>
#include <vector>

#include "solve/linear_solver.hpp"

namespace msfab {

class PcgSolver final : public LinearSolver {
 public:
  // Throws InputError for an invalid option.
  explicit PcgSolver(const LinearSolverOptions& options = {});

  void analyze(const SpMat& A) override;
  // Builds the preconditioner of A + shift I; returns false if a diagonal
  // entry (jacobi) or diagonal 3x3 block (block-jacobi3) is not positive
  // definite.
  bool factorize(const SpMat& A, double shift = 0.0) override;
  // Starts from x = 0. Throws NumericalError if the tolerance is not reached
  // within the iteration limit, or if a search direction has non-positive
  // curvature (then stats().positive_definite is false).
  VecX solve(const VecX& b) override;
  const LinearSolveStats& stats() const override { return stats_; }
  std::string name() const override { return "pcg"; }

 private:
  // z = M^{-1} r on entries [begin, end) (whole node blocks), returning
  // their part of r . z.
  double precondition(const double* r, double* z, Eigen::Index begin, Eigen::Index end) const;
  // z = M^{-1} r on all entries, returning r . z.
  double apply_preconditioner(const VecX& r, VecX& z) const;

  LinearSolverOptions options_;
  LinearSolveStats stats_;
  bool block_jacobi_ = false;
  Eigen::Index n_ = -1;  // -1: not analyzed
  std::uint64_t pattern_ = 0;
  // Positions in A.valuePtr() of the diagonal entries (jacobi) or of the 9
  // entries of each diagonal block, column-major (block-jacobi3); -1 where A
  // stores no entry.
  std::vector<std::int64_t> diagonal_positions_;
  // Inverse diagonal (jacobi) or inverse 3x3 blocks, column-major.
  std::vector<double> inverse_;
  const SpMat* matrix_ = nullptr;  // the matrix of the last successful factorize()
  double shift_ = 0.0;
};

}  // namespace msfab
