#include "solve/chebyshev_smoother.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdint>

#include "solve/sparse_ops.hpp"

namespace msfab {

namespace {

// Lanczos steps for the largest eigenvalue of D^-1 A. The largest Ritz value
// approaches it from below, quickly for the top of the spectrum.
constexpr int kLanczosSteps = 10;
// The smoothing interval is [kSafety * estimate / kSmoothingRange, kSafety *
// estimate]; the margin keeps the polynomial below 1 in magnitude on the
// whole spectrum when the estimate falls a little short.
constexpr double kSafety = 1.1;
constexpr double kSmoothingRange = 30.0;

// A reproducible start vector with no preferred direction: a hash of the
// index mapped to [-0.5, 0.5).
double start_entry(Eigen::Index i) {
  std::uint64_t h = static_cast<std::uint64_t>(i) + 0x9E3779B97F4A7C15ull;
  h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ull;
  h = (h ^ (h >> 27)) * 0x94D049BB133111EBull;
  h ^= h >> 31;
  return double(h >> 11) * (1.0 / 9007199254740992.0) - 0.5;
}

}  // namespace

bool ChebyshevSmoother::setup(const BlockMatrix& A, int degree, int threads) {
  pattern_ = &A;
  degree_ = degree;
  threads_ = threads;
  values_.resize(A.values.size());
  inverse_.resize(9 * std::size_t(A.rows));
  // An exact count whatever the thread count: the outcome is deterministic.
  const double bad_blocks =
      chunked_reduce(A.rows, threads, [&](Eigen::Index begin, Eigen::Index end) {
        double bad = 0.0;
        for (Eigen::Index i = begin; i < end; ++i) {
          for (std::size_t k = 9 * std::size_t(A.row_start[i]);
               k < 9 * std::size_t(A.row_start[i + 1]); ++k) {
            values_[k] = static_cast<float>(A.values[k]);
          }
          const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> block(
              A.values.data() + 9 * std::size_t(A.diagonal[i]));
          const Mat3 dense = block;
          const Eigen::LLT<Mat3> llt(dense);
          if (llt.info() != Eigen::Success || !dense.allFinite()) bad += 1.0;
          Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(inverse_.data() + 9 * i) =
              llt.solve(Mat3::Identity());
        }
        return bad;
      });
  if (bad_blocks != 0.0) return false;
  max_eigenvalue_ = estimate_max_eigenvalue();
  return std::isfinite(max_eigenvalue_) && max_eigenvalue_ > 0.0;
}

double ChebyshevSmoother::estimate_max_eigenvalue() const {
  const BlockMatrix& A = *pattern_;
  // Lanczos on D^-1 A, which is self-adjoint in the D inner product.
  const Eigen::Index n = A.unknowns();
  const double* values = A.values.data();
  auto diagonal_block = [&](Eigen::Index i) { return values + 9 * std::size_t(A.diagonal[i]); };
  // u . D u over nodes [begin, end).
  auto d_norm_part = [&](const VecX& u, Eigen::Index begin, Eigen::Index end) {
    double sum = 0.0;
    for (Eigen::Index i = begin; i < end; ++i) {
      const double* m = diagonal_block(i);
      const double* x = u.data() + 3 * i;
      for (int a = 0; a < 3; ++a)
        sum += x[a] * (m[3 * a] * x[0] + m[3 * a + 1] * x[1] + m[3 * a + 2] * x[2]);
    }
    return sum;
  };
  VecX v(n), previous = VecX::Zero(n), w(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = start_entry(i);
  double norm =
      std::sqrt(chunked_reduce(A.rows, threads_, [&](Eigen::Index begin, Eigen::Index end) {
        return d_norm_part(v, begin, end);
      }));
  if (!(norm > 0.0)) return 1.0;
  v /= norm;

  std::vector<double> alphas, betas;
  double beta = 0.0;
  for (int step = 0; step < kLanczosSteps; ++step) {
    // w = D^-1 A v and alpha = v . A v in one pass.
    const double alpha =
        chunked_reduce(A.rows, threads_, [&](Eigen::Index begin, Eigen::Index end) {
          double sum = 0.0;
          for (Eigen::Index i = begin; i < end; ++i) {
            double product[3];
            row_product(static_cast<int>(i), v.data(), product);
            apply_block_inverse(static_cast<int>(i), product, w.data() + 3 * i);
            sum += product[0] * v[3 * i] + product[1] * v[3 * i + 1] + product[2] * v[3 * i + 2];
          }
          return sum;
        });
    alphas.push_back(alpha);
    const double next_beta =
        std::sqrt(chunked_reduce(A.rows, threads_, [&](Eigen::Index begin, Eigen::Index end) {
          for (Eigen::Index k = 3 * begin; k < 3 * end; ++k)
            w[k] -= alpha * v[k] + beta * previous[k];
          return d_norm_part(w, begin, end);
        }));
    if (!(next_beta > 1e-12 * std::abs(alpha)) || step + 1 == kLanczosSteps) break;
    betas.push_back(next_beta);
    previous.swap(v);
    v = w / next_beta;
    beta = next_beta;
  }
  const Eigen::Index m = static_cast<Eigen::Index>(alphas.size());
  MatX tridiagonal = MatX::Zero(m, m);
  for (Eigen::Index k = 0; k < m; ++k) {
    tridiagonal(k, k) = alphas[k];
    if (k + 1 < m) {
      tridiagonal(k, k + 1) = betas[k];
      tridiagonal(k + 1, k) = betas[k];
    }
  }
  const Eigen::SelfAdjointEigenSolver<MatX> eigen(tridiagonal, Eigen::EigenvaluesOnly);
  return eigen.eigenvalues().maxCoeff();
}

void ChebyshevSmoother::residual(const VecX& b, const VecX& x, VecX& r) const {
  r.resize(b.size());
  parallel_row_ranges(pattern_->rows, resolve_thread_count(threads_), [&](int begin, int end) {
    for (int i = begin; i < end; ++i) {
      double product[3];
      row_product(i, x.data(), product);
      for (int a = 0; a < 3; ++a) r[3 * i + a] = b[3 * i + a] - product[a];
    }
  });
}

void ChebyshevSmoother::smooth(const VecX& b, VecX& x, bool zero_start) {
  const BlockMatrix& A = *pattern_;
  const double upper = kSafety * max_eigenvalue_;
  const double lower = upper / kSmoothingRange;
  const double theta = 0.5 * (upper + lower);
  const double delta = 0.5 * (upper - lower);
  const double sigma = theta / delta;
  const int team = resolve_thread_count(threads_);
  const Eigen::Index n = A.unknowns();
  step_.resize(n);
  next_.resize(n);

  // First step: x += D^-1 (b - A x) / theta.
  if (zero_start) {
    x.resize(n);
    parallel_row_ranges(A.rows, team, [&](int begin, int end) {
      for (int i = begin; i < end; ++i) {
        double r[3] = {b[3 * i] / theta, b[3 * i + 1] / theta, b[3 * i + 2] / theta};
        apply_block_inverse(i, r, step_.data() + 3 * i);
        for (int a = 0; a < 3; ++a) x[3 * i + a] = step_[3 * i + a];
      }
    });
  } else {
    parallel_row_ranges(A.rows, team, [&](int begin, int end) {
      for (int i = begin; i < end; ++i) {
        double r[3];
        row_product(i, x.data(), r);
        for (int a = 0; a < 3; ++a) r[a] = (b[3 * i + a] - r[a]) / theta;
        apply_block_inverse(i, r, step_.data() + 3 * i);
        for (int a = 0; a < 3; ++a) next_[3 * i + a] = x[3 * i + a] + step_[3 * i + a];
      }
    });
    x.swap(next_);
  }
  // Three-term recurrence of the Chebyshev iteration (Saad, Iterative
  // Methods for Sparse Linear Systems, Alg. 12.1).
  double rho = 1.0 / sigma;
  for (int k = 1; k < degree_; ++k) {
    const double rho_next = 1.0 / (2.0 * sigma - rho);
    const double keep = rho_next * rho;
    const double gain = 2.0 * rho_next / delta;
    parallel_row_ranges(A.rows, team, [&](int begin, int end) {
      for (int i = begin; i < end; ++i) {
        double r[3], z[3];
        row_product(i, x.data(), r);
        for (int a = 0; a < 3; ++a) r[a] = b[3 * i + a] - r[a];
        apply_block_inverse(i, r, z);
        for (int a = 0; a < 3; ++a) {
          double& s = step_[3 * i + a];
          s = keep * s + gain * z[a];
          next_[3 * i + a] = x[3 * i + a] + s;
        }
      }
    });
    x.swap(next_);
    rho = rho_next;
  }
}

}  // namespace msfab
