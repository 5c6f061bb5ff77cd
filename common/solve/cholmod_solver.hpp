#pragma once
// Sparse direct solver: CHOLMOD supernodal LL^T with a METIS nested-dissection
// ordering (AMD if METIS fails). The symbolic analysis is reused by every
// factorize() on the same pattern.
#include <memory>

#include "solve/linear_solver.hpp"

namespace msfab {

class CholmodSolver final : public LinearSolver {
 public:
  explicit CholmodSolver(const LinearSolverOptions& options = {});
  ~CholmodSolver() override;
  CholmodSolver(const CholmodSolver&) = delete;
  CholmodSolver& operator=(const CholmodSolver&) = delete;

  void analyze(const SpMat& A) override;
  bool factorize(const SpMat& A, double shift = 0.0) override;
  VecX solve(const VecX& b) override;
  // All columns of B in one pass over the factor (the supernodal solve works
  // on blocks of right-hand sides); stats() reports the relative residual of
  // the columns' sum.
  MatX solve_columns(const MatX& B);
  const LinearSolveStats& stats() const override { return stats_; }
  std::string name() const override { return "cholmod"; }

  // Ordering used by the last analyze(): "metis" or "amd" (empty before).
  const std::string& ordering() const { return ordering_; }
  // Nonzeros of the factor L (0 before the first analyze()).
  double factor_nonzeros() const;

 private:
  struct Cholmod;  // CHOLMOD workspace and factor; keeps cholmod.h out of this header
  std::unique_ptr<Cholmod> cholmod_;
  LinearSolverOptions options_;
  LinearSolveStats stats_;
  std::string ordering_;
  const SpMat* factorized_ = nullptr;  // the matrix of the last successful factorize()
  double shift_ = 0.0;
};

}  // namespace msfab
