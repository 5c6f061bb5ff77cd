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
  // Inverts the diagonal blocks of A and estimates the largest eigenvalue of
  // D^-1 A. Returns false if a diagonal block is not positive definite.
  bool setup(const BlockMatrix& A, int degree, int threads);

  // `degree` steps of the Chebyshev iteration for A x = b, starting from x
  // (or from zero if zero_start, without reading x).
  void smooth(const BlockMatrix& A, const VecX& b, VecX& x, bool zero_start);

  double max_eigenvalue() const { return max_eigenvalue_; }

 private:
  // z = D^-1 r for node i.
  void apply_block_inverse(int i, const double r[3], double* z) const {
    const double* m = inverse_.data() + 9 * std::size_t(i);
    z[0] = m[0] * r[0] + m[1] * r[1] + m[2] * r[2];
    z[1] = m[3] * r[0] + m[4] * r[1] + m[5] * r[2];
    z[2] = m[6] * r[0] + m[7] * r[1] + m[8] * r[2];
  }
  double estimate_max_eigenvalue(const BlockMatrix& A) const;

  std::vector<double> inverse_;  // inverse diagonal blocks, 9 per node, row-major
  double max_eigenvalue_ = 0.0;
  int degree_ = 2;
  int threads_ = 0;
  VecX step_, next_;  // workspace of smooth()
};

}  // namespace msfab
