#pragma once
// The Chebyshev / block-Jacobi smoothing kernels, written once for any
// operator given row by row: an assembled BlockMatrix (ChebyshevSmoother)
// or a matrix-free voxel operator (PeriodicGridMultigrid's finest level).
//
// An operator is a functor row_product(i, x, out) that writes the 3 entries
// of node row i of A x; the diagonal blocks D_i come as 9 row-major doubles
// per node. Every kernel touches each output row once, so results do not
// depend on the thread count.
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdint>
#include <vector>

#include "solve/block_matrix.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab::chebyshev {

// Lanczos steps for the largest eigenvalue of D^-1 A. The largest Ritz value
// approaches it from below, quickly for the top of the spectrum.
inline constexpr int kLanczosSteps = 10;
// The smoothing interval is [kSafety * estimate / kSmoothingRange, kSafety *
// estimate]; the margin keeps the polynomial below 1 in magnitude on the
// whole spectrum when the estimate falls a little short.
inline constexpr double kSafety = 1.1;
inline constexpr double kSmoothingRange = 30.0;

// z = D_i^-1 r with the inverse block `m` (row-major; double, or float
// where a large grid keeps its inverses in half the memory).
template <class Scalar>
inline void apply_block(const Scalar* m, const double r[3], double* z) {
  z[0] = m[0] * r[0] + m[1] * r[1] + m[2] * r[2];
  z[1] = m[3] * r[0] + m[4] * r[1] + m[5] * r[2];
  z[2] = m[6] * r[0] + m[7] * r[1] + m[8] * r[2];
}

// A reproducible start vector with no preferred direction: a hash of the
// index mapped to [-0.5, 0.5).
inline double start_entry(Eigen::Index i) {
  std::uint64_t h = static_cast<std::uint64_t>(i) + 0x9E3779B97F4A7C15ull;
  h = (h ^ (h >> 30)) * 0xBF58476D1CE4E5B9ull;
  h = (h ^ (h >> 27)) * 0x94D049BB133111EBull;
  h ^= h >> 31;
  return double(h >> 11) * (1.0 / 9007199254740992.0) - 0.5;
}

// inverse[9 i ..] = D_i^-1 for the blocks diagonal[9 i ..]. Returns the
// number of blocks that are not positive definite (an exact count, so the
// outcome does not depend on the thread count).
inline int invert_diagonal_blocks(int rows, const double* diagonal, std::vector<double>& inverse, int threads) {
  inverse.resize(9 * std::size_t(rows));
  const double bad = chunked_reduce(rows, threads, [&](Eigen::Index begin, Eigen::Index end) {
    double count = 0.0;
    for (Eigen::Index i = begin; i < end; ++i) {
      const Mat3 block = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(diagonal + 9 * i);
      const Eigen::LLT<Mat3> llt(block);
      if (llt.info() != Eigen::Success || !block.allFinite()) count += 1.0;
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(inverse.data() + 9 * i) = llt.solve(Mat3::Identity());
    }
    return count;
  });
  return static_cast<int>(bad);
}

// Largest eigenvalue of D^-1 A by Lanczos in the D inner product (D^-1 A is
// self-adjoint there). before_pass(v) runs before each product, as in smooth().
template <class RowProduct, class BeforePass>
double estimate_max_eigenvalue(int rows, const double* diagonal, const double* inverse, RowProduct&& row_product,
                               BeforePass&& before_pass, int threads) {
  const Eigen::Index n = 3 * Eigen::Index(rows);
  auto d_norm_part = [&](const VecX& u, Eigen::Index begin, Eigen::Index end) {
    double sum = 0.0;
    for (Eigen::Index i = begin; i < end; ++i) {
      const double* m = diagonal + 9 * i;
      const double* x = u.data() + 3 * i;
      for (int a = 0; a < 3; ++a) sum += x[a] * (m[3 * a] * x[0] + m[3 * a + 1] * x[1] + m[3 * a + 2] * x[2]);
    }
    return sum;
  };
  VecX v(n), previous = VecX::Zero(n), w(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = start_entry(i);
  const double norm = std::sqrt(
      chunked_reduce(rows, threads, [&](Eigen::Index begin, Eigen::Index end) { return d_norm_part(v, begin, end); }));
  if (!(norm > 0.0)) return 1.0;
  v /= norm;

  std::vector<double> alphas, betas;
  double beta = 0.0;
  for (int step = 0; step < kLanczosSteps; ++step) {
    // w = D^-1 A v and alpha = v . A v in one pass.
    before_pass(v);
    const double alpha = chunked_reduce(rows, threads, [&](Eigen::Index begin, Eigen::Index end) {
      double sum = 0.0;
      for (Eigen::Index i = begin; i < end; ++i) {
        double product[3];
        row_product(static_cast<int>(i), v.data(), product);
        apply_block(inverse + 9 * i, product, w.data() + 3 * i);
        sum += product[0] * v[3 * i] + product[1] * v[3 * i + 1] + product[2] * v[3 * i + 2];
      }
      return sum;
    });
    alphas.push_back(alpha);
    const double next_beta = std::sqrt(chunked_reduce(rows, threads, [&](Eigen::Index begin, Eigen::Index end) {
      for (Eigen::Index k = 3 * begin; k < 3 * end; ++k) w[k] -= alpha * v[k] + beta * previous[k];
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

// r = b - A x.
template <class RowProduct>
void residual(int rows, RowProduct&& row_product, const VecX& b, const VecX& x, VecX& r, int threads) {
  r.resize(b.size());
  parallel_row_ranges(rows, resolve_thread_count(threads), [&](int begin, int end) {
    for (int i = begin; i < end; ++i) {
      double product[3];
      row_product(i, x.data(), product);
      for (int a = 0; a < 3; ++a) r[3 * i + a] = b[3 * i + a] - product[a];
    }
  });
}

// `degree` steps of the Chebyshev iteration for A x = b (Saad, Iterative
// Methods for Sparse Linear Systems, Alg. 12.1) on the interval set by
// max_eigenvalue, starting from x or from zero. step and next are workspace.
//
// before_pass(x) runs before every pass that calls row_product on x: an
// operator that is cheaper applied whole (element by element) computes A x
// there and row_product reads it back.
template <class InverseScalar, class RowProduct, class BeforePass>
void smooth(int rows, const InverseScalar* inverse, double max_eigenvalue, int degree, RowProduct&& row_product,
            BeforePass&& before_pass, const VecX& b, VecX& x, bool zero_start, VecX& step, VecX& next, int threads) {
  const double upper = kSafety * max_eigenvalue;
  const double lower = upper / kSmoothingRange;
  const double theta = 0.5 * (upper + lower);
  const double delta = 0.5 * (upper - lower);
  const double sigma = theta / delta;
  const int team = resolve_thread_count(threads);
  const Eigen::Index n = 3 * Eigen::Index(rows);
  step.resize(n);
  next.resize(n);

  // First step: x += D^-1 (b - A x) / theta.
  if (zero_start) {
    x.resize(n);
    parallel_row_ranges(rows, team, [&](int begin, int end) {
      for (int i = begin; i < end; ++i) {
        const double r[3] = {b[3 * i] / theta, b[3 * i + 1] / theta, b[3 * i + 2] / theta};
        apply_block(inverse + 9 * std::size_t(i), r, step.data() + 3 * i);
        for (int a = 0; a < 3; ++a) x[3 * i + a] = step[3 * i + a];
      }
    });
  } else {
    before_pass(x);
    parallel_row_ranges(rows, team, [&](int begin, int end) {
      for (int i = begin; i < end; ++i) {
        double r[3];
        row_product(i, x.data(), r);
        for (int a = 0; a < 3; ++a) r[a] = (b[3 * i + a] - r[a]) / theta;
        apply_block(inverse + 9 * std::size_t(i), r, step.data() + 3 * i);
        for (int a = 0; a < 3; ++a) next[3 * i + a] = x[3 * i + a] + step[3 * i + a];
      }
    });
    x.swap(next);
  }
  double rho = 1.0 / sigma;
  for (int k = 1; k < degree; ++k) {
    const double rho_next = 1.0 / (2.0 * sigma - rho);
    const double keep = rho_next * rho;
    const double gain = 2.0 * rho_next / delta;
    before_pass(x);
    parallel_row_ranges(rows, team, [&](int begin, int end) {
      for (int i = begin; i < end; ++i) {
        double r[3], z[3];
        row_product(i, x.data(), r);
        for (int a = 0; a < 3; ++a) r[a] = b[3 * i + a] - r[a];
        apply_block(inverse + 9 * std::size_t(i), r, z);
        for (int a = 0; a < 3; ++a) {
          double& s = step[3 * i + a];
          s = keep * s + gain * z[a];
          next[3 * i + a] = x[3 * i + a] + s;
        }
      }
    });
    x.swap(next);
    rho = rho_next;
  }
}

}  // namespace msfab::chebyshev
