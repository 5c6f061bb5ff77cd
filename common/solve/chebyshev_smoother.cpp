#include "solve/chebyshev_smoother.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "solve/chebyshev_kernels.hpp"

namespace msfab {

void ChebyshevSmoother::upper_product(const VecX& x) const {
  const BlockMatrix& A = *pattern_;
  product_.resize(A.unknowns());
  const int chunks = static_cast<int>(chunk_start_.size()) - 1;
  const int team = resolve_thread_count(threads_);
  const int* column = A.column.data();
#pragma omp parallel num_threads(team) if (A.rows > 4096)
  {
#pragma omp for schedule(static)
    for (Eigen::Index k = 0; k < product_.size(); ++k) product_[k] = 0.0;
    for (int parity = 0; parity < 2; ++parity) {
#pragma omp for schedule(static)
      for (int c = parity; c < chunks; c += 2) {
        for (int i = chunk_start_[std::size_t(c)]; i < chunk_start_[std::size_t(c) + 1]; ++i) {
          const double* xi = x.data() + 3 * std::size_t(i);
          const float* m = values_.data() + 9 * std::size_t(first_upper_[std::size_t(i)]);
          double y0 = 0.0, y1 = 0.0, y2 = 0.0;
          add_block_product(m, xi, y0, y1, y2);  // the diagonal block
          for (int slot = A.diagonal[std::size_t(i)] + 1; slot < A.row_start[i + 1]; ++slot) {
            m += 9;
            const std::size_t j = std::size_t(column[slot]);
            add_block_product(m, x.data() + 3 * j, y0, y1, y2);
            double* yj = product_.data() + 3 * j;
            add_transposed_block_product(m, xi, yj[0], yj[1], yj[2]);
          }
          double* yi = product_.data() + 3 * std::size_t(i);
          yi[0] += y0, yi[1] += y1, yi[2] += y2;
        }
      }
    }
  }
}

bool ChebyshevSmoother::setup(const BlockMatrix& A, int degree, int threads, SmootherValues values,
                              const std::vector<int>* upper) {
  if (upper && values != SmootherValues::single_upper)
    throw std::logic_error(
        "ChebyshevSmoother: an operator held by its upper blocks needs SmootherValues::single_upper");
  return setup_with(A, degree, threads, values, upper);
}

bool ChebyshevSmoother::setup(const BlockMatrix& A, int degree, int threads, std::vector<int>&& upper) {
  if (!setup_with(A, degree, threads, SmootherValues::single_upper, &upper)) return false;
  std::vector<int>().swap(upper);  // the products read the upper blocks row by row
  return true;
}

bool ChebyshevSmoother::setup_with(const BlockMatrix& A, int degree, int threads, SmootherValues values,
                                   const std::vector<int>* held_by_upper) {
  pattern_ = &A;
  degree_ = degree;
  threads_ = threads;
  values_kind_ = values;
  std::vector<float>().swap(values_);
  std::vector<std::int64_t>().swap(first_upper_);
  std::vector<int>().swap(chunk_start_);
  VecX().swap(product_);
  if (values == SmootherValues::single) {
    values_.resize(A.values.size());
    chunked_for(A.rows, threads, [&](Eigen::Index begin, Eigen::Index end) {
      for (std::size_t k = 9 * std::size_t(A.row_start[begin]); k < 9 * std::size_t(A.row_start[end]); ++k)
        values_[k] = static_cast<float>(A.values[k]);
    });
  } else if (values == SmootherValues::single_upper) {
    // The upper product needs every block's mirror; the numbering refuses
    // a pattern that is not symmetric (std::logic_error).
    if (!held_by_upper) upper_block_numbering(A, threads);
    values_.resize(9 * upper_block_count(A));
    first_upper_.assign(std::size_t(A.rows) + 1, 0);
    int reach = 1;
    for (int i = 0; i < A.rows; ++i) {
      first_upper_[std::size_t(i) + 1] =
          first_upper_[std::size_t(i)] + (A.row_start[i + 1] - A.diagonal[std::size_t(i)]);
      if (A.row_start[i + 1] > A.row_start[i])
        reach = std::max(reach, A.column[std::size_t(A.row_start[i + 1]) - 1] - i);
    }
    chunk_start_.clear();
    for (int begin = 0; begin < A.rows; begin += reach) chunk_start_.push_back(begin);
    chunk_start_.push_back(A.rows);
    chunked_for(A.rows, threads, [&](Eigen::Index begin, Eigen::Index end) {
      for (Eigen::Index i = begin; i < end; ++i)
        for (int slot = A.diagonal[std::size_t(i)]; slot < A.row_start[i + 1]; ++slot) {
          // Row by row, as upper_product() reads them; a numbering only
          // locates the source where A itself is held by its upper blocks.
          const std::size_t block = std::size_t(first_upper_[std::size_t(i)] + (slot - A.diagonal[std::size_t(i)]));
          const double* source = A.values.data() + stored_block(held_by_upper, slot);
          for (int e = 0; e < 9; ++e) values_[9 * block + e] = static_cast<float>(source[e]);
        }
    });
  }
  const auto diagonal_block = [&](Eigen::Index i) {
    return A.values.data() + stored_block(held_by_upper, A.diagonal[std::size_t(i)]);
  };
  diagonal_.resize(9 * std::size_t(A.rows));
  chunked_for(A.rows, threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index i = begin; i < end; ++i) std::copy_n(diagonal_block(i), 9, diagonal_.data() + 9 * i);
  });
  if (chebyshev::invert_diagonal_blocks(A.rows, diagonal_.data(), inverse_, threads) != 0) return false;
  max_eigenvalue_ = chebyshev::estimate_max_eigenvalue(
      A.rows, diagonal_.data(), inverse_.data(), [&](int i, const double* x, double out[3]) { row_product(i, x, out); },
      [&](const VecX& x) { before_pass(x); }, threads);
  std::vector<double>().swap(diagonal_);  // the smoothing uses the inverses only
  return std::isfinite(max_eigenvalue_) && max_eigenvalue_ > 0.0;
}

void ChebyshevSmoother::residual(const VecX& b, const VecX& x, VecX& r) const {
  before_pass(x);
  chebyshev::residual(
      pattern_->rows, [&](int i, const double* y, double out[3]) { row_product(i, y, out); }, b, x, r, threads_);
}

void ChebyshevSmoother::smooth(const VecX& b, VecX& x, bool zero_start) {
  chebyshev::smooth(
      pattern_->rows, inverse_.data(), max_eigenvalue_, degree_,
      [&](int i, const double* y, double out[3]) { row_product(i, y, out); }, [&](const VecX& y) { before_pass(y); }, b,
      x, zero_start, step_, next_, threads_);
}

}  // namespace msfab
