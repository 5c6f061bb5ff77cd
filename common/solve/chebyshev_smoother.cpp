#include "solve/chebyshev_smoother.hpp"

#include <algorithm>
#include <cmath>

#include "solve/chebyshev_kernels.hpp"

namespace msfab {

bool ChebyshevSmoother::setup(const BlockMatrix& A, int degree, int threads, bool single_precision) {
  pattern_ = &A;
  degree_ = degree;
  threads_ = threads;
  single_precision_ = single_precision;
  values_.resize(single_precision ? A.values.size() : 0);
  values_.shrink_to_fit();
  diagonal_.resize(9 * std::size_t(A.rows));
  chunked_for(A.rows, threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index i = begin; i < end; ++i) {
      if (single_precision)
        for (std::size_t k = 9 * std::size_t(A.row_start[i]); k < 9 * std::size_t(A.row_start[i + 1]); ++k)
          values_[k] = static_cast<float>(A.values[k]);
      std::copy_n(A.values.data() + 9 * std::size_t(A.diagonal[i]), 9, diagonal_.data() + 9 * i);
    }
  });
  if (chebyshev::invert_diagonal_blocks(A.rows, diagonal_.data(), inverse_, threads) != 0) return false;
  max_eigenvalue_ = chebyshev::estimate_max_eigenvalue(
      A.rows, diagonal_.data(), inverse_.data(),
      [&](int i, const double* x, double out[3]) { row_product(i, x, out); }, [](const VecX&) {}, threads);
  std::vector<double>().swap(diagonal_);  // the smoothing uses the inverses only
  return std::isfinite(max_eigenvalue_) && max_eigenvalue_ > 0.0;
}

void ChebyshevSmoother::residual(const VecX& b, const VecX& x, VecX& r) const {
  chebyshev::residual(pattern_->rows, [&](int i, const double* y, double out[3]) { row_product(i, y, out); }, b,
                      x, r, threads_);
}

void ChebyshevSmoother::smooth(const VecX& b, VecX& x, bool zero_start) {
  chebyshev::smooth(pattern_->rows, inverse_.data(), max_eigenvalue_, degree_,
                    [&](int i, const double* y, double out[3]) { row_product(i, y, out); }, [](const VecX&) {}, b, x,
                    zero_start, step_, next_, threads_);
}

}  // namespace msfab
