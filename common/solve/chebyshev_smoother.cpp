#include "solve/chebyshev_smoother.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "solve/chebyshev_kernels.hpp"

namespace msfab {

void ChebyshevSmoother::upper_row_product(int i, const double* x, double out[3]) const {
  double y0 = 0.0, y1 = 0.0, y2 = 0.0;
  const int* column = pattern_->column.data();
  for (int slot = pattern_->row_start[i]; slot < pattern_->row_start[i + 1]; ++slot) {
    const float* m = values_.data() + 9 * std::size_t(block_of_slot_[std::size_t(slot)]);
    const double* xj = x + 3 * std::size_t(column[slot]);
    if (column[slot] >= i)
      add_block_product(m, xj, y0, y1, y2);
    else
      add_transposed_block_product(m, xj, y0, y1, y2);
  }
  out[0] = y0;
  out[1] = y1;
  out[2] = y2;
}

bool ChebyshevSmoother::setup(const BlockMatrix& A, int degree, int threads, SmootherValues values) {
  pattern_ = &A;
  degree_ = degree;
  threads_ = threads;
  values_kind_ = values;
  std::vector<float>().swap(values_);
  std::vector<int>().swap(block_of_slot_);
  if (values == SmootherValues::single) {
    values_.resize(A.values.size());
    chunked_for(A.rows, threads, [&](Eigen::Index begin, Eigen::Index end) {
      for (std::size_t k = 9 * std::size_t(A.row_start[begin]); k < 9 * std::size_t(A.row_start[end]); ++k)
        values_[k] = static_cast<float>(A.values[k]);
    });
  } else if (values == SmootherValues::single_upper) {
    // Number the upper blocks row by row, then point every slot at its block.
    std::vector<int> first_upper(std::size_t(A.rows) + 1, 0);
    for (int i = 0; i < A.rows; ++i)
      first_upper[std::size_t(i) + 1] = first_upper[std::size_t(i)] + (A.row_start[i + 1] - A.diagonal[std::size_t(i)]);
    values_.resize(9 * std::size_t(first_upper.back()));
    block_of_slot_.resize(std::size_t(A.num_blocks()));
    const long long unmatched = chunked_reduce(A.rows, threads, [&](Eigen::Index begin, Eigen::Index end) {
      long long missing = 0;
      for (Eigen::Index i = begin; i < end; ++i) {
        for (int slot = A.row_start[i]; slot < A.row_start[i + 1]; ++slot) {
          const int j = A.column[std::size_t(slot)];
          if (j >= i) {
            const int block = first_upper[std::size_t(i)] + (slot - A.diagonal[std::size_t(i)]);
            block_of_slot_[std::size_t(slot)] = block;
            for (int e = 0; e < 9; ++e)
              values_[9 * std::size_t(block) + e] = static_cast<float>(A.values[9 * std::size_t(slot) + e]);
            continue;
          }
          // Block (j, i) sits in row j, above its diagonal.
          const auto begin_j = A.column.begin() + A.diagonal[std::size_t(j)];
          const auto end_j = A.column.begin() + A.row_start[std::size_t(j) + 1];
          const auto it = std::lower_bound(begin_j, end_j, static_cast<int>(i));
          if (it == end_j || *it != i) {
            ++missing;
            continue;
          }
          block_of_slot_[std::size_t(slot)] =
              first_upper[std::size_t(j)] + static_cast<int>(it - A.column.begin()) - A.diagonal[std::size_t(j)];
        }
      }
      return missing;
    });
    if (unmatched != 0) throw std::logic_error("ChebyshevSmoother: the block pattern is not symmetric");
  }
  diagonal_.resize(9 * std::size_t(A.rows));
  chunked_for(A.rows, threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index i = begin; i < end; ++i)
      std::copy_n(A.values.data() + 9 * std::size_t(A.diagonal[i]), 9, diagonal_.data() + 9 * i);
  });
  if (chebyshev::invert_diagonal_blocks(A.rows, diagonal_.data(), inverse_, threads) != 0) return false;
  max_eigenvalue_ = chebyshev::estimate_max_eigenvalue(
      A.rows, diagonal_.data(), inverse_.data(), [&](int i, const double* x, double out[3]) { row_product(i, x, out); },
      [](const VecX&) {}, threads);
  std::vector<double>().swap(diagonal_);  // the smoothing uses the inverses only
  return std::isfinite(max_eigenvalue_) && max_eigenvalue_ > 0.0;
}

void ChebyshevSmoother::residual(const VecX& b, const VecX& x, VecX& r) const {
  chebyshev::residual(
      pattern_->rows, [&](int i, const double* y, double out[3]) { row_product(i, y, out); }, b, x, r, threads_);
}

void ChebyshevSmoother::smooth(const VecX& b, VecX& x, bool zero_start) {
  chebyshev::smooth(
      pattern_->rows, inverse_.data(), max_eigenvalue_, degree_,
      [&](int i, const double* y, double out[3]) { row_product(i, y, out); }, [](const VecX&) {}, b, x, zero_start,
      step_, next_, threads_);
}

}  // namespace msfab
