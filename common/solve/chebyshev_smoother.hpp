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
#include <cstdint>
#include <vector>

#include "solve/block_matrix.hpp"

namespace msfab {

// Multigrid levels with more blocks than this (level 1 and 2 of a voxel
// model of millions of voxels) are held by their upper blocks: the
// smoother's copy in single precision once set up (single_upper below),
// and level 1 of the voxel multigrid in double from its assembly on
// (ComponentMultigrid). Memory over speed on the largest matrices.
constexpr int kUpperLevelBlocks = 1 << 20;

// How a smoother holds its operator's values.
enum class SmootherValues {
  // Every block in single precision: a product moves half the bytes of A's
  // (the smoother is only a preconditioner).
  single,
  // Only the blocks on and above the diagonal, in single precision. A
  // product reads each of them once and applies it twice, B x_j to row i
  // and B^T x_i to row j, by chunks of rows (upper_product()). About 40%
  // fewer bytes than `single` and an exactly symmetric operator: for levels
  // too large to hold otherwise.
  single_upper,
  // A's own double values: where the stiffness contrast exceeds what
  // single precision resolves (about 1e7), rounding the stiff entries
  // changes the operator by more than the soft entries are worth, so the
  // rounded matrix can be indefinite and the V-cycle is no longer a
  // positive definite preconditioner.
  double_values,
};

class ChebyshevSmoother {
 public:
  // Takes A's values as `values` says, inverts the diagonal blocks and
  // estimates the largest eigenvalue of D^-1 A. A's pattern must stay alive
  // until the next setup() (and A's values too with double_values); for
  // single_upper it must be symmetric (std::logic_error if not). With
  // `upper` (upper_block_numbering(A)), A's values are held by its upper
  // blocks, and `values` must be single_upper. Returns false if a diagonal
  // block is not positive definite.
  bool setup(const BlockMatrix& A, int degree, int threads, SmootherValues values = SmootherValues::single,
             const std::vector<int>* upper = nullptr);
  // The same for A held by its upper blocks (single_upper), releasing the
  // numbering `upper` once set up (the products do not need it): on a large
  // level it is a fifth of the single values. `upper` is left empty, or as
  // it was where set-up fails.
  bool setup(const BlockMatrix& A, int degree, int threads, std::vector<int>&& upper);

  // `degree` steps of the Chebyshev iteration for A x = b, starting from x
  // (or from zero if zero_start, without reading x).
  void smooth(const VecX& b, VecX& x, bool zero_start);
  // r = b - A x with the smoother's operator. Not to be called on one
  // smoother from two threads at once: with single_upper it forms A x in
  // the smoother's workspace.
  void residual(const VecX& b, const VecX& x, VecX& r) const;

  double max_eigenvalue() const { return max_eigenvalue_; }
  int degree() const { return degree_; }

 private:
  // Row i of A x. With single_upper, A x is formed whole by
  // before_pass(x) and read back here.
  void row_product(int i, const double* x, double out[3]) const {
    switch (values_kind_) {
      case SmootherValues::single: block_row_product(*pattern_, values_.data(), i, x, out); break;
      case SmootherValues::single_upper: {
        const double* y = product_.data() + 3 * std::size_t(i);
        out[0] = y[0], out[1] = y[1], out[2] = y[2];
        break;
      }
      case SmootherValues::double_values: block_row_product(*pattern_, pattern_->values.data(), i, x, out); break;
    }
  }
  // What a pass over the rows needs first: A x into product_ (single_upper).
  void before_pass(const VecX& x) const {
    if (values_kind_ == SmootherValues::single_upper) upper_product(x);
  }
  // product_ = A x from the upper blocks. Rows go in chunks of at least the
  // pattern's reach (the largest j - i of a block), so a chunk's
  // transposed blocks land in it or the next one: the even chunks run in
  // parallel, then the odd ones, and every entry sums its terms in an
  // order fixed by the pattern, whatever the thread count.
  void upper_product(const VecX& x) const;
  // setup(); `held_by_upper` (or null): A's values are A's upper blocks in
  // that numbering.
  bool setup_with(const BlockMatrix& A, int degree, int threads, SmootherValues values,
                  const std::vector<int>* held_by_upper);
  const BlockMatrix* pattern_ = nullptr;
  SmootherValues values_kind_ = SmootherValues::single;
  // single: A's values in single precision, laid out like A.values.
  // single_upper: A's blocks on and above the diagonal (9 each, row-major,
  // row by row), the first of each row, the chunks' first rows, and the
  // product's workspace.
  std::vector<float> values_;
  std::vector<std::int64_t> first_upper_;
  std::vector<int> chunk_start_;
  mutable VecX product_;
  std::vector<double> diagonal_;  // diagonal blocks, 9 per node, row-major (released after setup)
  std::vector<double> inverse_;   // their inverses
  double max_eigenvalue_ = 0.0;
  int degree_ = 2;
  int threads_ = 0;
  VecX step_, next_;  // workspace of smooth()
};

}  // namespace msfab
