#include "solve/pcg_solver.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "core/errors.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {

// Chunks hold whole 3x3 node blocks, so block-Jacobi can work chunk by chunk.
static_assert(kReductionChunk % 3 == 0, "reduction chunks must hold whole node blocks");

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string format_number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g", value);
  return text;
}

}  // namespace

PcgSolver::PcgSolver(const LinearSolverOptions& options)
    : options_(options), block_jacobi_(options.pcg_preconditioner == "block-jacobi3") {
  validate_linear_solver_options(options);
}

void PcgSolver::analyze(const SpMat& A) {
  const auto start = std::chrono::steady_clock::now();
  if (A.rows() != A.cols()) {
    throw std::invalid_argument("PcgSolver::analyze: matrix is " + std::to_string(A.rows()) +
                                "x" + std::to_string(A.cols()) + ", not square");
  }
  const Eigen::Index n = A.rows();
  if (block_jacobi_ && n % 3 != 0) {
    throw InputError("linear solver option pcg_preconditioner 'block-jacobi3' needs a multiple "
                     "of 3 unknowns (3 per node), but the system has " + std::to_string(n));
  }
  stats_ = LinearSolveStats{};
  matrix_ = nullptr;
  const int block = block_jacobi_ ? 3 : 1;
  diagonal_positions_.assign(static_cast<std::size_t>(n * block), -1);
  chunked_for(n / block, options_.threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index k = begin; k < end; ++k) {
      for (int col = 0; col < block; ++col) {
        for (int row = 0; row < block; ++row) {
          diagonal_positions_[static_cast<std::size_t>(k * block * block + row + block * col)] =
              find_entry(A, static_cast<int>(k * block + row), static_cast<int>(k * block + col));
        }
      }
    }
  });
  n_ = n;
  pattern_ = pattern_fingerprint(A);
  stats_.analyze_seconds = seconds_since(start);
}

bool PcgSolver::factorize(const SpMat& A, double shift) {
  const auto start = std::chrono::steady_clock::now();
  if (n_ < 0) throw std::logic_error("PcgSolver::factorize called before analyze");
  if (A.rows() != n_ || A.cols() != n_ || pattern_fingerprint(A) != pattern_) {
    throw std::invalid_argument(
        "PcgSolver::factorize: the matrix pattern differs from the one given to analyze()");
  }
  matrix_ = nullptr;
  const double* values = A.valuePtr();
  auto entry = [&](std::size_t slot) {
    const std::int64_t position = diagonal_positions_[slot];
    return position >= 0 ? values[position] : 0.0;
  };
  inverse_.resize(diagonal_positions_.size());
  const int block = block_jacobi_ ? 3 : 1;
  // Count of blocks that are not positive definite; an integer sum is exact,
  // so the outcome does not depend on the thread count.
  const double bad_blocks =
      chunked_reduce(n_ / block, options_.threads, [&](Eigen::Index begin, Eigen::Index end) {
        double bad = 0.0;
        for (Eigen::Index k = begin; k < end; ++k) {
          if (!block_jacobi_) {
            const double d = entry(static_cast<std::size_t>(k)) + shift;
            if (!(d > 0.0) || !std::isfinite(d)) bad += 1.0;
            inverse_[static_cast<std::size_t>(k)] = 1.0 / d;
            continue;
          }
          Mat3 diagonal_block;
          for (int a = 0; a < 9; ++a) {
            diagonal_block(a) = entry(static_cast<std::size_t>(9 * k + a));
          }
          diagonal_block.diagonal().array() += shift;
          const Eigen::LLT<Mat3> llt(diagonal_block);
          if (llt.info() != Eigen::Success || !diagonal_block.allFinite()) bad += 1.0;
          const Mat3 inverse = llt.solve(Mat3::Identity());
          for (int a = 0; a < 9; ++a) inverse_[static_cast<std::size_t>(9 * k + a)] = inverse(a);
        }
        return bad;
      });
  stats_.positive_definite = bad_blocks == 0.0;
  stats_.factorize_seconds = seconds_since(start);
  if (!stats_.positive_definite) return false;
  matrix_ = &A;
  shift_ = shift;
  return true;
}

double PcgSolver::precondition(const double* r, double* z, Eigen::Index begin,
                               Eigen::Index end) const {
  const double* inverse = inverse_.data();
  double rz = 0.0;
  if (!block_jacobi_) {
    for (Eigen::Index i = begin; i < end; ++i) {
      z[i] = inverse[i] * r[i];
      rz += r[i] * z[i];
    }
    return rz;
  }
  for (Eigen::Index i = begin; i < end; i += 3) {
    const double* m = inverse + 3 * i;  // block i / 3, 9 entries column-major
    for (int row = 0; row < 3; ++row) {
      z[i + row] = m[row] * r[i] + m[row + 3] * r[i + 1] + m[row + 6] * r[i + 2];
      rz += r[i + row] * z[i + row];
    }
  }
  return rz;
}

double PcgSolver::apply_preconditioner(const VecX& r, VecX& z) const {
  z.resize(r.size());
  return chunked_reduce(n_, options_.threads, [&](Eigen::Index begin, Eigen::Index end) {
    return precondition(r.data(), z.data(), begin, end);
  });
}

VecX PcgSolver::solve(const VecX& b) {
  const auto start = std::chrono::steady_clock::now();
  if (matrix_ == nullptr) {
    throw NumericalError(
        "PCG solve without a valid preconditioner (the last factorize() found a diagonal "
        "entry or block not positive definite, or none was done)");
  }
  if (b.size() != n_) {
    throw std::invalid_argument("PcgSolver::solve: right-hand side has " +
                                std::to_string(b.size()) + " entries, matrix has " +
                                std::to_string(n_) + " rows");
  }
  const SpMat& A = *matrix_;
  const int threads = options_.threads;
  const Eigen::Index n = n_;
  stats_.iterations = 0;
  stats_.relative_residual = 0.0;

  VecX x = VecX::Zero(n);
  const double b_norm = std::sqrt(parallel_dot(b, b, threads));
  if (b_norm == 0.0) {
    stats_.solve_seconds = seconds_since(start);
    return x;
  }
  const double target = options_.pcg_tolerance * b_norm;
  VecX r = b;
  VecX z, q;
  double rz = apply_preconditioner(r, z);
  VecX p = z;
  double r_norm = b_norm;
  std::string history = "1";
  const int max_iterations = options_.pcg_max_iterations;
  const int history_stride = std::max(1, max_iterations / 8);

  int iteration = 0;
  for (;;) {
    if (r_norm <= target) {
      // The recursively updated residual drifts from b - A x in floating
      // point; accept only the true residual, else restart from it.
      VecX ax;
      symmetric_spmv(A, x, ax, shift_, threads);
      chunked_for(n, threads, [&](Eigen::Index begin, Eigen::Index end) {
        for (Eigen::Index i = begin; i < end; ++i) r[i] = b[i] - ax[i];
      });
      r_norm = std::sqrt(parallel_dot(r, r, threads));
      if (r_norm <= target) break;
      rz = apply_preconditioner(r, z);
      p = z;
    }
    if (iteration >= max_iterations) {
      stats_.iterations = iteration;
      stats_.relative_residual = r_norm / b_norm;
      stats_.solve_seconds = seconds_since(start);
      throw NumericalError("PCG (" + options_.pcg_preconditioner + ") did not converge: "
                           "relative residual " + format_number(r_norm / b_norm) + " after " +
                           std::to_string(iteration) + " iterations (tolerance " +
                           format_number(options_.pcg_tolerance) + ", pcg_max_iterations " +
                           std::to_string(max_iterations) + "); relative residual every " +
                           std::to_string(history_stride) + " iterations: " + history);
    }
    const double curvature = symmetric_spmv_dot(A, p, q, shift_, threads);
    if (!(curvature > 0.0) || !std::isfinite(curvature)) {
      stats_.positive_definite = false;
      stats_.iterations = iteration;
      stats_.relative_residual = r_norm / b_norm;
      stats_.solve_seconds = seconds_since(start);
      throw NumericalError("PCG met non-positive curvature p'(A + shift I)p = " +
                           format_number(curvature) + " at iteration " +
                           std::to_string(iteration) +
                           ": the matrix is not positive definite; factorize with a larger shift");
    }
    const double alpha = rz / curvature;
    // One pass: update x and r, precondition r, and sum r.r and r.z.
    const Eigen::Vector2d sums =
        chunked_reduce(n, threads, [&](Eigen::Index begin, Eigen::Index end) {
          double rr = 0.0;
          for (Eigen::Index i = begin; i < end; ++i) {
            x[i] += alpha * p[i];
            r[i] -= alpha * q[i];
            rr += r[i] * r[i];
          }
          return Eigen::Vector2d(rr, precondition(r.data(), z.data(), begin, end));
        });
    r_norm = std::sqrt(sums[0]);
    const double rz_next = sums[1];
    const double beta = rz_next / rz;
    rz = rz_next;
    chunked_for(n, threads, [&](Eigen::Index begin, Eigen::Index end) {
      for (Eigen::Index i = begin; i < end; ++i) p[i] = z[i] + beta * p[i];
    });
    ++iteration;
    if (iteration % history_stride == 0) {
      history += ", " + format_number(r_norm / b_norm);
    }
  }
  stats_.iterations = iteration;
  stats_.relative_residual = r_norm / b_norm;
  stats_.solve_seconds = seconds_since(start);
  return x;
}

}  // namespace msfab
