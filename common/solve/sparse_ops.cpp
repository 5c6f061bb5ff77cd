#include "solve/sparse_ops.hpp"

#include <omp.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace msfab {

namespace {

// Entries of column j occupy [outer[j], column_end(A, j)) of the index and
// value arrays; uncompressed matrices leave gaps after each column.
inline Eigen::Index column_end(const SpMat& A, Eigen::Index j) {
  return A.isCompressed() ? A.outerIndexPtr()[j + 1] : A.outerIndexPtr()[j] + A.innerNonZeroPtr()[j];
}

void require_square_match(const SpMat& A, const VecX& x, const char* what) {
  if (A.rows() != A.cols() || x.size() != A.cols()) {
    throw std::invalid_argument(std::string(what) + ": matrix is " + std::to_string(A.rows()) + "x" +
                                std::to_string(A.cols()) + " but the vector has " + std::to_string(x.size()) +
                                " entries");
  }
}

// Rows [begin, end) of y = (A + shift I) x, returning their contribution to x . y.
inline double spmv_rows(const SpMat& A, const double* x, double* y, double shift, Eigen::Index begin,
                        Eigen::Index end) {
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  const double* values = A.valuePtr();
  double dot = 0.0;
  for (Eigen::Index j = begin; j < end; ++j) {
    double sum = shift * x[j];
    const Eigen::Index stop = column_end(A, j);
    for (Eigen::Index k = outer[j]; k < stop; ++k) sum += values[k] * x[inner[k]];
    y[j] = sum;
    dot += x[j] * sum;
  }
  return dot;
}

}  // namespace

int resolve_thread_count(int threads) { return threads > 0 ? threads : omp_get_max_threads(); }

double parallel_dot(const VecX& a, const VecX& b, int threads) {
  if (a.size() != b.size()) {
    throw std::invalid_argument("parallel_dot: vector sizes differ (" + std::to_string(a.size()) + " vs " +
                                std::to_string(b.size()) + ")");
  }
  return chunked_reduce(a.size(), threads, [&](Eigen::Index begin, Eigen::Index end) {
    return a.segment(begin, end - begin).dot(b.segment(begin, end - begin));
  });
}

double symmetric_spmv_dot(const SpMat& A, const VecX& x, VecX& y, double shift, int threads) {
  require_square_match(A, x, "symmetric_spmv");
  y.resize(A.rows());
  const double* xp = x.data();
  double* yp = y.data();
  return chunked_reduce(A.cols(), threads,
                        [&](Eigen::Index begin, Eigen::Index end) { return spmv_rows(A, xp, yp, shift, begin, end); });
}

void symmetric_spmv(const SpMat& A, const VecX& x, VecX& y, double shift, int threads) {
  symmetric_spmv_dot(A, x, y, shift, threads);
}

double relative_residual(const SpMat& A, const VecX& x, const VecX& b, double shift, int threads) {
  require_square_match(A, b, "relative_residual");
  VecX residual;
  symmetric_spmv(A, x, residual, shift, threads);
  residual = b - residual;
  const double residual_norm = std::sqrt(parallel_dot(residual, residual, threads));
  const double rhs_norm = std::sqrt(parallel_dot(b, b, threads));
  if (rhs_norm == 0.0) {
    return residual_norm == 0.0 ? 0.0 : std::numeric_limits<double>::infinity();
  }
  return residual_norm / rhs_norm;
}

std::int64_t find_entry(const SpMat& A, int row, int col) {
  const int* inner = A.innerIndexPtr();
  const int* first = inner + A.outerIndexPtr()[col];
  const int* last = inner + column_end(A, col);
  const int* hit = std::lower_bound(first, last, row);
  return (hit != last && *hit == row) ? static_cast<std::int64_t>(hit - inner) : -1;
}

std::uint64_t pattern_fingerprint(const SpMat& A) {
  // FNV-1a style mixing over 32-bit words; collisions would need a different
  // pattern with identical size, nonzero count and a matching 64-bit hash.
  std::uint64_t hash = 1469598103934665603ull;
  auto mix = [&hash](std::uint64_t word) {
    hash ^= word;
    hash *= 1099511628211ull;
  };
  mix(static_cast<std::uint64_t>(A.rows()));
  mix(static_cast<std::uint64_t>(A.cols()));
  mix(static_cast<std::uint64_t>(A.nonZeros()));
  const int* outer = A.outerIndexPtr();
  const int* inner = A.innerIndexPtr();
  for (Eigen::Index j = 0; j < A.outerSize(); ++j) {
    const Eigen::Index stop = column_end(A, j);
    mix(static_cast<std::uint64_t>(stop - outer[j]));
    for (Eigen::Index k = outer[j]; k < stop; ++k) mix(static_cast<std::uint32_t>(inner[k]));
  }
  return hash;
}

}  // namespace msfab
