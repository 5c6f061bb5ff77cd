#include "solve/multigrid_solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "core/errors.hpp"
#include "solve/block_matrix.hpp"
#include "solve/chebyshev_smoother.hpp"
#include "solve/grid_transfer.hpp"
#include "solve/node_lattice.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {

namespace {

// Deeper hierarchies than this never occur for meshes that fit in memory.
constexpr int kMaxLevels = 24;
// Smoother degree on the coarse levels, relative to mg_smoother_degree.
constexpr int kCoarseDegreeFactor = 2;
// Coarse corrections per visit of a level below the finest (2: W-cycle).
constexpr int kCoarseCorrections = 2;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string format_number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g", value);
  return text;
}

}  // namespace

struct MultigridSolver::Level {
  NodeLattice lattice;
  BlockMatrix matrix;
  std::vector<char> decoupled;              // unknowns whose row holds only the diagonal
  std::unique_ptr<GridTransfer> to_coarse;  // null on the coarsest level
  ChebyshevSmoother smoother;
  VecX rhs, solution, residual;  // V-cycle workspace
};

MultigridSolver::MultigridSolver(const LinearSolverOptions& options) : options_(options) {
  validate_linear_solver_options(options);
  if (options.mg_coarse_unknowns < 3) {
    throw InputError("linear solver option mg_coarse_unknowns must be at least 3, got " +
                     std::to_string(options.mg_coarse_unknowns));
  }
  if (options.mg_smoother_degree < 1 || options.mg_smoother_degree > 10) {
    throw InputError("linear solver option mg_smoother_degree must lie in 1..10, got " +
                     std::to_string(options.mg_smoother_degree));
  }
}

MultigridSolver::~MultigridSolver() = default;

void MultigridSolver::analyze(const SpMat& A) {
  const auto start = std::chrono::steady_clock::now();
  if (A.rows() != A.cols()) {
    throw std::invalid_argument("MultigridSolver::analyze: matrix is " + std::to_string(A.rows()) +
                                "x" + std::to_string(A.cols()) + ", not square");
  }
  levels_.clear();
  ready_ = false;
  n_ = -1;
  stats_ = LinearSolveStats{};
  if (A.rows() == 0) {  // nothing to solve, no geometry needed
    n_ = 0;
    pattern_ = pattern_fingerprint(A);
    stats_.analyze_seconds = seconds_since(start);
    return;
  }
  if (!options_.node_positions) {
    throw InputError(
        "pcg-mg needs a voxel mesh: LinearSolverOptions::node_positions is not set "
        "(give the rest positions of the mesh nodes, or use 'cholmod' or 'pcg')");
  }
  const Eigen::Index nodes = options_.node_positions->rows();
  if (3 * nodes != A.rows()) {
    throw InputError("pcg-mg needs a voxel mesh: node_positions has " + std::to_string(nodes) +
                     " nodes (" + std::to_string(3 * nodes) + " unknowns) but the matrix has " +
                     std::to_string(A.rows()) + " rows");
  }

  auto fine = std::make_unique<Level>();
  fine->lattice = lattice_from_positions(*options_.node_positions);
  fine->matrix = block_pattern(A);
  levels_.push_back(std::move(fine));
  while (levels_.back()->matrix.unknowns() >= options_.mg_coarse_unknowns &&
         static_cast<int>(levels_.size()) < kMaxLevels) {
    Level& level = *levels_.back();
    NodeLattice coarse_lattice = coarsen_lattice(level.lattice);
    // A lattice only one or two points thick in every direction stops shrinking.
    if (10 * std::int64_t(coarse_lattice.num_nodes()) > 9 * std::int64_t(level.lattice.num_nodes()))
      break;
    level.to_coarse = std::make_unique<GridTransfer>(level.lattice, coarse_lattice, level.matrix);
    auto coarse = std::make_unique<Level>();
    coarse->matrix = level.to_coarse->coarse_pattern();
    coarse->lattice = std::move(coarse_lattice);
    levels_.push_back(std::move(coarse));
  }

  coarsest_ = sparse_pattern(levels_.back()->matrix);
  coarse_solver_.analyzePattern(coarsest_);

  n_ = A.rows();
  pattern_ = pattern_fingerprint(A);
  stats_.analyze_seconds = seconds_since(start);
}

bool MultigridSolver::factorize(const SpMat& A, double shift) {
  const auto start = std::chrono::steady_clock::now();
  if (n_ < 0) throw std::logic_error("MultigridSolver::factorize called before analyze");
  if (A.rows() != n_ || A.cols() != n_ || pattern_fingerprint(A) != pattern_) {
    throw std::invalid_argument(
        "MultigridSolver::factorize: the matrix pattern differs from the one given to analyze()");
  }
  ready_ = false;
  stats_.positive_definite = false;
  if (n_ == 0) {
    stats_.positive_definite = ready_ = true;
    stats_.factorize_seconds = seconds_since(start);
    return true;
  }
  const int threads = options_.threads;
  copy_block_values(A, shift, levels_.front()->matrix, threads);
  bool definite = true;
  for (std::size_t l = 0; l < levels_.size(); ++l) {
    Level& level = *levels_[l];
    level.decoupled = decoupled_unknowns(level.matrix, threads);
    if (!level.to_coarse) break;
    level.to_coarse->galerkin_product(level.matrix, level.decoupled, levels_[l + 1]->matrix,
                                      threads);
    // Coarse levels are small: smoothing them harder costs little and keeps
    // the under-resolved high-contrast coarse operators from slowing CG down.
    const int degree = (l == 0 ? 1 : kCoarseDegreeFactor) * options_.mg_smoother_degree;
    if (!level.smoother.setup(level.matrix, degree, threads)) {
      definite = false;
      break;
    }
  }
  if (definite) {
    copy_to_sparse(levels_.back()->matrix, coarsest_);
    coarse_solver_.factorize(coarsest_);
    definite = coarse_solver_.info() == Eigen::Success;
  }
  stats_.positive_definite = definite;
  ready_ = definite;
  stats_.factorize_seconds = seconds_since(start);
  return definite;
}

void MultigridSolver::cycle(std::size_t index, const VecX& rhs, VecX& solution) {
  if (index + 1 == levels_.size()) {
    solution = coarse_solver_.solve(rhs);
    return;
  }
  Level& level = *levels_[index];
  Level& coarse = *levels_[index + 1];
  const int threads = options_.threads;
  level.smoother.smooth(rhs, solution, /*zero_start=*/true);
  // Below the finest level two coarse corrections per visit (a W-cycle):
  // the repeated correction is cheap there and keeps the cycle close to a
  // two-grid method. Repeating the same symmetric correction keeps the
  // cycle symmetric.
  const int corrections = index == 0 ? 1 : kCoarseCorrections;
  for (int c = 0; c < corrections; ++c) {
    level.smoother.residual(rhs, solution, level.residual);
    level.to_coarse->restrict_to_coarse(level.residual, level.decoupled, coarse.rhs, threads);
    cycle(index + 1, coarse.rhs, coarse.solution);
    level.to_coarse->add_prolongation(coarse.solution, level.decoupled, solution, threads);
  }
  level.smoother.smooth(rhs, solution, /*zero_start=*/false);
}

VecX MultigridSolver::apply_preconditioner(const VecX& r) {
  if (!ready_) {
    throw NumericalError("pcg-mg preconditioner applied without a successful factorize()");
  }
  if (r.size() != n_) {
    throw std::invalid_argument("MultigridSolver::apply_preconditioner: vector has " +
                                std::to_string(r.size()) + " entries, matrix has " +
                                std::to_string(n_) + " rows");
  }
  VecX z;
  cycle(0, r, z);
  return z;
}

VecX MultigridSolver::solve(const VecX& b) {
  const auto start = std::chrono::steady_clock::now();
  if (!ready_) {
    throw NumericalError(
        "pcg-mg solve without a valid preconditioner (the last factorize() found a matrix "
        "that is not positive definite, or none was done); factorize with a larger shift first");
  }
  if (b.size() != n_) {
    throw std::invalid_argument("MultigridSolver::solve: right-hand side has " +
                                std::to_string(b.size()) + " entries, matrix has " +
                                std::to_string(n_) + " rows");
  }
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
  const BlockMatrix& A = levels_.front()->matrix;  // A + shift I
  const double target = options_.pcg_tolerance * b_norm;
  const int max_iterations = options_.pcg_max_iterations;
  const int history_stride = std::max(1, max_iterations / 8);
  std::string history = "1";
  int iteration = 0;
  double r_norm = b_norm;

  auto fail = [&](const std::string& why) {
    stats_.iterations = iteration;
    stats_.relative_residual = r_norm / b_norm;
    stats_.solve_seconds = seconds_since(start);
    throw NumericalError(why);
  };
  auto not_definite = [&](const std::string& what, double value) {
    stats_.positive_definite = false;
    fail("pcg-mg met " + what + " = " + format_number(value) + " at iteration " +
         std::to_string(iteration) + " (relative residual " + format_number(r_norm / b_norm) +
         "): the matrix is not positive definite; factorize with a larger shift");
  };

  VecX r = b, z, p, q(n);
  cycle(0, r, z);
  double rz = parallel_dot(r, z, threads);
  if (!(rz > 0.0) || !std::isfinite(rz)) not_definite("r' M^-1 r", rz);
  p = z;
  for (;;) {
    if (r_norm <= target) {
      // The recursive residual drifts from b - A x; accept only the true one.
      block_multiply(A, x, q, threads);
      chunked_for(n, threads, [&](Eigen::Index begin, Eigen::Index end) {
        for (Eigen::Index i = begin; i < end; ++i) r[i] = b[i] - q[i];
      });
      r_norm = std::sqrt(parallel_dot(r, r, threads));
      if (r_norm <= target) break;
      cycle(0, r, z);
      rz = parallel_dot(r, z, threads);
      if (!(rz > 0.0) || !std::isfinite(rz)) not_definite("r' M^-1 r", rz);
      p = z;
    }
    if (iteration >= max_iterations) {
      fail("pcg-mg did not converge: relative residual " + format_number(r_norm / b_norm) +
           " after " + std::to_string(iteration) + " iterations (tolerance " +
           format_number(options_.pcg_tolerance) + ", pcg_max_iterations " +
           std::to_string(max_iterations) + "); relative residual every " +
           std::to_string(history_stride) + " iterations: " + history);
    }
    // q = A p and p . q in one pass over the matrix.
    const double curvature =
        chunked_reduce(A.rows, threads, [&](Eigen::Index begin, Eigen::Index end) {
          double sum = 0.0;
          for (Eigen::Index i = begin; i < end; ++i) {
            block_row_product(A, static_cast<int>(i), p.data(), q.data() + 3 * i);
            sum += p[3 * i] * q[3 * i] + p[3 * i + 1] * q[3 * i + 1] + p[3 * i + 2] * q[3 * i + 2];
          }
          return sum;
        });
    if (!(curvature > 0.0) || !std::isfinite(curvature)) {
      not_definite("non-positive curvature p'(A + shift I)p", curvature);
    }
    const double alpha = rz / curvature;
    const double rr = chunked_reduce(n, threads, [&](Eigen::Index begin, Eigen::Index end) {
      double sum = 0.0;
      for (Eigen::Index i = begin; i < end; ++i) {
        x[i] += alpha * p[i];
        r[i] -= alpha * q[i];
        sum += r[i] * r[i];
      }
      return sum;
    });
    r_norm = std::sqrt(rr);
    ++iteration;
    if (iteration % history_stride == 0) history += ", " + format_number(r_norm / b_norm);
    if (r_norm <= target) continue;
    cycle(0, r, z);
    const double rz_next = parallel_dot(r, z, threads);
    if (!(rz_next > 0.0) || !std::isfinite(rz_next)) not_definite("r' M^-1 r", rz_next);
    const double beta = rz_next / rz;
    rz = rz_next;
    chunked_for(n, threads, [&](Eigen::Index begin, Eigen::Index end) {
      for (Eigen::Index i = begin; i < end; ++i) p[i] = z[i] + beta * p[i];
    });
  }
  stats_.iterations = iteration;
  stats_.relative_residual = r_norm / b_norm;
  stats_.solve_seconds = seconds_since(start);
  return x;
}

Eigen::Index MultigridSolver::level_unknowns(int level) const {
  return levels_.at(static_cast<std::size_t>(level))->matrix.unknowns();
}

SpMat MultigridSolver::level_operator(int level) const {
  const BlockMatrix& M = levels_.at(static_cast<std::size_t>(level))->matrix;
  SpMat S = sparse_pattern(M);
  copy_to_sparse(M, S);
  return S;
}

SpMat MultigridSolver::prolongation(int level) const {
  const Level& fine = *levels_.at(static_cast<std::size_t>(level));
  if (!fine.to_coarse) {
    throw std::invalid_argument("MultigridSolver::prolongation: level " + std::to_string(level) +
                                " is the coarsest");
  }
  return fine.to_coarse->prolongation(fine.decoupled);
}

}  // namespace msfab
