#include "solve/pcg_solver.hpp"

#include <Eigen/Cholesky>
#include <chrono>
#include <cmath>
#include <string>

#include "core/errors.hpp"
#include "core/timing.hpp"
#include "solve/conjugate_gradient.hpp"
#include "solve/solver_checks.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {

// Chunks hold whole 3x3 node blocks, so block-Jacobi can work chunk by chunk.
static_assert(kReductionChunk % 3 == 0, "reduction chunks must hold whole node blocks");

namespace {}  // namespace

PcgSolver::PcgSolver(const LinearSolverOptions& options)
    : options_(options), block_jacobi_(options.pcg_preconditioner == "block-jacobi3") {
  validate_linear_solver_options(options);
}

void PcgSolver::analyze(const SpMat& A) {
  const auto start = std::chrono::steady_clock::now();
  require_square(A, "PcgSolver");
  const Eigen::Index n = A.rows();
  if (block_jacobi_ && n % 3 != 0) {
    throw InputError(
        "linear solver option pcg_preconditioner 'block-jacobi3' needs a multiple "
        "of 3 unknowns (3 per node), but the system has " +
        std::to_string(n));
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
  require_analyzed_pattern(A, n_, pattern_, "PcgSolver");
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
  const double bad_blocks = chunked_reduce(n_ / block, options_.threads, [&](Eigen::Index begin, Eigen::Index end) {
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

double PcgSolver::precondition(const double* r, double* z, Eigen::Index begin, Eigen::Index end) const {
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
  if (matrix_ == nullptr) {
    throw NumericalError(
        "PCG solve without a valid preconditioner (the last factorize() found a diagonal "
        "entry or block not positive definite, or none was done)");
  }
  require_rhs_size(b, n_, "PcgSolver");
  const SpMat& A = *matrix_;
  const int threads = options_.threads;
  CgOperator op;
  op.multiply = [&](const VecX& x, VecX& y) { symmetric_spmv(A, x, y, shift_, threads); };
  op.multiply_dot = [&](const VecX& x, VecX& y) { return symmetric_spmv_dot(A, x, y, shift_, threads); };
  CgPreconditioner preconditioner;
  preconditioner.apply = [this](const VecX& r, VecX& z) { return apply_preconditioner(r, z); };
  preconditioner.apply_chunk = [this](const double* r, double* z, Eigen::Index begin, Eigen::Index end) {
    return precondition(r, z, begin, end);
  };
  CgSettings settings;
  settings.tolerance = options_.pcg_tolerance;
  settings.max_iterations = options_.pcg_max_iterations;
  settings.max_iterations_key = options_.pcg_max_iterations_key;
  settings.threads = threads;
  settings.label = "PCG (" + options_.pcg_preconditioner + ")";
  settings.curvature_label = "PCG";
  return conjugate_gradient(op, preconditioner, b, settings, stats_);
}

}  // namespace msfab
