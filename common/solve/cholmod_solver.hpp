#pragma once
// Sparse direct solver: CHOLMOD supernodal LL^T with a METIS nested-dissection
// ordering (AMD if METIS fails), or simplicial LDL^T for symmetric indefinite
// matrices (LinearSolverOptions::indefinite). The symbolic analysis is reused by every
// factorize() on the same pattern.
#include <memory>
#include <vector>

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
  // An analysis whose factor ends with the unknowns `last`, in that order,
  // the others ordered among themselves by METIS (AMD if it fails). Then
  // the inverse restricted to those unknowns needs the factor's trailing
  // block alone: with P A P^T = L L^T and L_ll its last |last| rows and
  // columns, (A^{-1})_{last,last} = (L_ll L_ll^T)^{-1}. The contact solve
  // of a Newmark step (its Delassus matrix G^T H^{-1} G, G supported on the
  // contact nodes) takes it from there instead of one solve per contact
  // column. factorize() reuses it as it does analyze(); InputError on an
  // index out of range or repeated.
  void analyze_with_last(const SpMat& A, const std::vector<int>& last);
  // The unknowns the current analysis puts last (empty after analyze()).
  const std::vector<int>& last_unknowns() const { return last_; }
  // L_ll of the last successful factorize() after analyze_with_last(): dense
  // and lower triangular, rows and columns in the order of last_unknowns().
  MatX trailing_factor() const;
  const LinearSolveStats& stats() const override { return stats_; }
  std::string name() const override { return "cholmod"; }

  // Ordering used by the last analysis: "metis" or "amd" (empty before), or
  // "given unknowns last" after analyze_with_last().
  const std::string& ordering() const { return ordering_; }
  // Nonzeros of the factor L (0 before the first analyze()).
  double factor_nonzeros() const;
  // With LinearSolverOptions::indefinite: the negative pivots of the last
  // successful factorize(), i.e. the negative eigenvalues of A + shift I
  // (0 otherwise).
  int negative_pivots() const { return negative_pivots_; }

 private:
  void reset_analysis();  // frees the factor and forgets the analysis
  struct Cholmod;         // CHOLMOD workspace and factor; keeps cholmod.h out of this header
  std::unique_ptr<Cholmod> cholmod_;
  LinearSolverOptions options_;
  LinearSolveStats stats_;
  std::string ordering_;
  std::vector<int> last_;
  const SpMat* factorized_ = nullptr;  // the matrix of the last successful factorize()
  double shift_ = 0.0;
  int negative_pivots_ = 0;
};

}  // namespace msfab
