#pragma once
// Chebyshev polynomial smoother preconditioned by 3x3 block Jacobi (one
// block per node), the multigrid smoother of pcg-mg.
//
// The polynomial damps the error components of D^-1 A with eigenvalues in
// [lambda_max / kSmoothingRange, lambda_max]; lambda_max is estimated by a
// few Lanczos steps. Unlike Gauss-Seidel it needs only matrix-vector
// products (parallel, deterministic), and unlike damped Jacobi it needs no
// damping factor tuned to the Poisson ratio or the stiffness contrast. The
// same polynomial is used before and after the coarse correction, so the
// V-cycle is symmetric.
#include <vector>

#include "solve/block_matrix.hpp"

namespace msfab {

class ChebyshevSmoother {
 public:
  // Takes A's values in single precision as the smoother's operator (a
  // product then moves half the bytes; the smoother is only a
  // preconditioner), inverts the diagonal blocks and estimates the largest
  // eigenvalue of D^-1 A. Only the blocks on and above the diagonal are
  // kept; a block below it is read as its mirror transposed, so the rounded
  // operator is exactly symmetric and costs a little over half the bytes.
  // A's pattern must be symmetric (std::logic_error if not) and stay alive
  // until the next setup(). Returns false if a diagonal block is not
  // positive definite.
  //
  // With single_precision = false the smoother uses A's double values. That
  // is needed where the stiffness contrast exceeds what single precision
  // resolves (about 1e7): rounding the stiff entries then changes the
  // operator by more than the soft entries are worth, so the rounded matrix
  // can be indefinite and the V-cycle is no longer a positive definite
  // preconditioner.
  bool setup(const BlockMatrix& A, int degree, int threads, bool single_precision = true);

  // `degree` steps of the Chebyshev iteration for A x = b, starting from x
  // (or from zero if zero_start, without reading x).
  void smooth(const VecX& b, VecX& x, bool zero_start);
  // r = b - A x with the smoother's operator.
  void residual(const VecX& b, const VecX& x, VecX& r) const;

  double max_eigenvalue() const { return max_eigenvalue_; }
  int degree() const { return degree_; }

 private:
  void row_product(int i, const double* x, double out[3]) const {
    if (single_precision_)
      upper_row_product(i, x, out);
    else
      block_row_product(*pattern_, pattern_->values.data(), i, x, out);
  }
  void upper_row_product(int i, const double* x, double out[3]) const;
  const BlockMatrix* pattern_ = nullptr;
  bool single_precision_ = true;
  // If single_precision_: A's blocks on and above the diagonal in single
  // precision (9 each, row-major), and per slot of A the block it reads
  // (for a slot below the diagonal, its mirror's, used transposed).
  std::vector<float> values_;
  std::vector<int> block_of_slot_;
  std::vector<double> diagonal_;  // diagonal blocks, 9 per node, row-major (released after setup)
  std::vector<double> inverse_;   // their inverses
  double max_eigenvalue_ = 0.0;
  int degree_ = 2;
  int threads_ = 0;
  VecX step_, next_;  // workspace of smooth()
};

}  // namespace msfab
