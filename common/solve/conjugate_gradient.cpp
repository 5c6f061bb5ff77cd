#include "solve/conjugate_gradient.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "core/errors.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {

namespace {

std::string format_number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g", value);
  return text;
}

// One pass over the vectors: x += alpha p, r -= alpha q, and the sums r.r
// and, where the preconditioner works chunk by chunk, z = M^-1 r with r.z
// (else r.z is 0 and z untouched).
Eigen::Vector2d step_and_residual(double alpha, const VecX& p, const VecX& q, const CgPreconditioner& M, int threads,
                                  VecX& x, VecX& r, VecX& z) {
  const Eigen::Index n = x.size();
  if (M.apply_chunk)
    return chunked_reduce(n, threads, [&](Eigen::Index begin, Eigen::Index end) {
      double rr = 0.0;
      for (Eigen::Index i = begin; i < end; ++i) {
        x[i] += alpha * p[i];
        r[i] -= alpha * q[i];
        rr += r[i] * r[i];
      }
      return Eigen::Vector2d(rr, M.apply_chunk(r.data(), z.data(), begin, end));
    });
  const double rr = chunked_reduce(n, threads, [&](Eigen::Index begin, Eigen::Index end) {
    double sum = 0.0;
    for (Eigen::Index i = begin; i < end; ++i) {
      x[i] += alpha * p[i];
      r[i] -= alpha * q[i];
      sum += r[i] * r[i];
    }
    return sum;
  });
  return Eigen::Vector2d(rr, 0.0);
}

}  // namespace

CgSetup multigrid_cg_setup(std::function<void(const VecX&, VecX&)> multiply,
                           std::function<void(const VecX&, VecX&)> cycle, double tolerance, int max_iterations,
                           int threads, const std::string& label) {
  CgSetup cg;
  if (multiply) {
    cg.op.multiply = multiply;
    cg.op.multiply_dot = [multiply, threads](const VecX& x, VecX& y) {
      multiply(x, y);
      return parallel_dot(x, y, threads);
    };
  }
  cg.preconditioner.apply = [cycle, threads](const VecX& r, VecX& z) {
    cycle(r, z);
    return parallel_dot(r, z, threads);
  };
  cg.preconditioner.check_definite = true;
  cg.settings.tolerance = tolerance;
  cg.settings.max_iterations = max_iterations;
  cg.settings.threads = threads;
  cg.settings.label = label;
  cg.settings.curvature_label = label;
  cg.settings.curvature_message_has_residual = true;
  return cg;
}

VecX conjugate_gradient(const CgOperator& A, const CgPreconditioner& M, const VecX& b, const CgSettings& settings,
                        LinearSolveStats& stats) {
  const auto start = std::chrono::steady_clock::now();
  auto record = [&](int iterations, double relative_residual) {
    stats.iterations = iterations;
    stats.relative_residual = relative_residual;
    stats.solve_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  const int threads = settings.threads;
  const Eigen::Index n = b.size();
  record(0, 0.0);
  VecX x = VecX::Zero(n);
  const double b_norm = std::sqrt(parallel_dot(b, b, threads));
  if (b_norm == 0.0) return x;

  const double target = settings.tolerance * b_norm;
  const int max_iterations = settings.max_iterations;
  const int history_stride = std::max(1, max_iterations / 8);
  std::string history = "1";
  int iteration = 0;
  double r_norm = b_norm;

  auto fail = [&](const std::string& why) {
    record(iteration, r_norm / b_norm);
    throw NumericalError(why);
  };
  auto not_definite = [&](const std::string& what, double value) {
    stats.positive_definite = false;
    fail(settings.curvature_label + " met " + what + " = " + format_number(value) + " at iteration " +
         std::to_string(iteration) +
         (settings.curvature_message_has_residual ? " (relative residual " + format_number(r_norm / b_norm) + ")"
                                                  : std::string()) +
         ": the matrix is not positive definite; factorize with a larger shift");
  };
  auto precondition = [&](const VecX& residual, VecX& z) {
    const double rz = M.apply(residual, z);
    if (M.check_definite && (!(rz > 0.0) || !std::isfinite(rz))) {
      not_definite("r' M^-1 r", rz);
    }
    return rz;
  };

  // M^-1 r and A p live at different times (A p is consumed by the update
  // of r before M^-1 r of the new r is formed, and M^-1 r by the update of
  // p before A p is formed), so they share one vector: CG holds b, x, r, p
  // and this one.
  VecX r = b, p, zq;
  VecX& z = zq;
  VecX& q = zq;
  double rz = precondition(r, z);
  p = z;
  for (;;) {
    if (r_norm <= target) {
      // The recursively updated residual drifts from b - A x in floating
      // point; accept only the true residual, else restart from it.
      A.multiply(x, q);
      chunked_for(n, threads, [&](Eigen::Index begin, Eigen::Index end) {
        for (Eigen::Index i = begin; i < end; ++i) r[i] = b[i] - q[i];
      });
      r_norm = std::sqrt(parallel_dot(r, r, threads));
      if (r_norm <= target) break;
      rz = precondition(r, z);
      p = z;
    }
    if (iteration >= max_iterations) {
      fail(settings.label + " did not converge: relative residual " + format_number(r_norm / b_norm) + " after " +
           std::to_string(iteration) + " iterations (tolerance " + format_number(settings.tolerance) +
           ", iteration limit " + std::to_string(max_iterations) +
           (settings.max_iterations_key.empty() ? std::string() : " set by " + settings.max_iterations_key) +
           "); relative residual every " + std::to_string(history_stride) + " iterations: " + history);
    }
    const double curvature = A.multiply_dot(p, q);
    if (!(curvature > 0.0) || !std::isfinite(curvature)) {
      not_definite("non-positive curvature p'(A + shift I)p", curvature);
    }
    const double alpha = rz / curvature;
    const Eigen::Vector2d sums = step_and_residual(alpha, p, q, M, threads, x, r, z);
    r_norm = std::sqrt(sums[0]);
    double rz_next = sums[1];
    ++iteration;
    if (iteration % history_stride == 0) history += ", " + format_number(r_norm / b_norm);
    if (settings.progress && iteration % std::max(1, settings.progress_stride) == 0)
      settings.progress(iteration, r_norm / b_norm);
    // Converged by the recursive residual: the true-residual check above
    // either stops or restarts with a fresh direction, so skip the update.
    if (r_norm <= target) continue;
    if (!M.apply_chunk) {
      rz_next = precondition(r, z);
    } else if (M.check_definite && (!(rz_next > 0.0) || !std::isfinite(rz_next))) {
      not_definite("r' M^-1 r", rz_next);
    }
    const double beta = rz_next / rz;
    rz = rz_next;
    chunked_for(n, threads, [&](Eigen::Index begin, Eigen::Index end) {
      for (Eigen::Index i = begin; i < end; ++i) p[i] = z[i] + beta * p[i];
    });
  }
  record(iteration, r_norm / b_norm);
  return x;
}

}  // namespace msfab
