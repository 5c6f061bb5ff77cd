#include "solve/multigrid_solver.hpp"

#include <chrono>
#include <stdexcept>
#include <string>

#include "core/errors.hpp"
#include "core/timing.hpp"
#include "solve/block_matrix.hpp"
#include "solve/chebyshev_smoother.hpp"
#include "solve/conjugate_gradient.hpp"
#include "solve/grid_transfer.hpp"
#include "solve/multigrid_cycle.hpp"
#include "solve/node_lattice.hpp"
#include "solve/solver_checks.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {

namespace {

// Deeper hierarchies than this never occur for meshes that fit in memory.
constexpr int kMaxLevels = 24;
using namespace multigrid_cycle;

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
  require_square(A, "MultigridSolver");
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
    throw InputError("pcg-mg needs a voxel mesh: node_positions has " + std::to_string(nodes) + " nodes (" +
                     std::to_string(3 * nodes) + " unknowns) but the matrix has " + std::to_string(A.rows()) + " rows");
  }

  auto fine = std::make_unique<Level>();
  fine->lattice = lattice_from_positions(*options_.node_positions);
  fine->matrix = block_pattern(A);
  levels_.push_back(std::move(fine));
  while (levels_.back()->matrix.unknowns() >= options_.mg_coarse_unknowns &&
         static_cast<int>(levels_.size()) < kMaxLevels) {
    Level& level = *levels_.back();
    // Levels whose matrix reaches beyond lattice neighbours (elements of
    // mixed sizes) coarsen by injection (node_lattice.hpp).
    const int reach = lattice_reach(level.lattice, level.matrix);
    const bool wide = reach > 1;
    NodeLattice coarse_lattice = wide ? coarsen_lattice_by_injection(level.lattice) : coarsen_lattice(level.lattice);
    // A lattice only one or two points thick in every direction stops
    // shrinking. On a mesh of mixed element sizes nodes sit several lattice
    // steps apart where elements are large: there a level keeps its nodes
    // while the lattice halves, and the level after it shrinks, so only a
    // lattice that no longer halves stops it.
    if (10 * std::int64_t(coarse_lattice.num_nodes()) > 9 * std::int64_t(level.lattice.num_nodes()) &&
        (!wide || coarse_lattice.dims == level.lattice.dims))
      break;
    level.to_coarse = std::make_unique<GridTransfer>(level.lattice, coarse_lattice, level.matrix, reach);
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
  require_analyzed_pattern(A, n_, pattern_, "MultigridSolver");
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
    level.to_coarse->galerkin_product(level.matrix, level.decoupled, levels_[l + 1]->matrix, threads);
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
  // The assembled levels: Chebyshev / block-Jacobi smoothing, lattice
  // transfers that skip decoupled unknowns, CHOLMOD on the coarsest.
  struct Levels : multigrid_cycle::SmoothedLevels<decltype(levels_)> {
    MultigridSolver& s;
    bool is_coarsest(std::size_t i) const { return i + 1 == s.levels_.size(); }
    // On a mesh of mixed element sizes, a coarser level that keeps most of
    // this one's unknowns (large elements) costs as much as this one: a W
    // there would double the cycle's cost at every such level, so it is
    // visited once. Meshes of equal voxels keep the V-over-W cycle.
    int corrections(std::size_t i) const {
      const Level& level = *s.levels_[i];
      if (i > 0 && !level.to_coarse->neighbour_coupled() &&
          4 * std::int64_t(s.levels_[i + 1]->matrix.rows) > 3 * std::int64_t(level.matrix.rows))
        return 1;
      return SmoothedLevels::corrections(i);
    }
    void solve_coarsest(std::size_t, const VecX& b, VecX& x) { x = s.coarse_solver_.solve(b); }
    void restrict_to_coarse(std::size_t i, const VecX& r, VecX& coarse_rhs) {
      const Level& level = *s.levels_[i];
      level.to_coarse->restrict_to_coarse(r, level.decoupled, coarse_rhs, s.options_.threads);
    }
    void add_prolongation(std::size_t i, const VecX& coarse_x, VecX& x) {
      const Level& level = *s.levels_[i];
      level.to_coarse->add_prolongation(coarse_x, level.decoupled, x, s.options_.threads);
    }
  } levels{{levels_}, *this};
  multigrid_cycle::cycle(levels, index, rhs, solution);
}

VecX MultigridSolver::apply_preconditioner(const VecX& r) {
  if (!ready_) {
    throw NumericalError("pcg-mg preconditioner applied without a successful factorize()");
  }
  if (r.size() != n_) {
    throw std::invalid_argument("MultigridSolver::apply_preconditioner: vector has " + std::to_string(r.size()) +
                                " entries, matrix has " + std::to_string(n_) + " rows");
  }
  VecX z;
  cycle(0, r, z);
  return z;
}

VecX MultigridSolver::solve(const VecX& b) {
  if (!ready_) {
    throw NumericalError(
        "pcg-mg solve without a valid preconditioner (the last factorize() found a matrix "
        "that is not positive definite, or none was done); factorize with a larger shift first");
  }
  require_rhs_size(b, n_, "MultigridSolver");
  const int threads = options_.threads;
  CgSetup cg = multigrid_cg_setup(
      nullptr, [this](const VecX& r, VecX& z) { cycle(0, r, z); }, options_.pcg_tolerance, options_.pcg_max_iterations,
      threads, "pcg-mg");
  cg.settings.max_iterations_key = options_.pcg_max_iterations_key;
  if (n_ > 0) {
    const BlockMatrix& A = levels_.front()->matrix;  // A + shift I
    cg.op.multiply = [&A, threads](const VecX& x, VecX& y) { block_multiply(A, x, y, threads); };
    // y = A x and x . y in one pass over the matrix.
    cg.op.multiply_dot = [&A, threads](const VecX& x, VecX& y) {
      y.resize(A.unknowns());
      return chunked_reduce(A.rows, threads, [&](Eigen::Index begin, Eigen::Index end) {
        double sum = 0.0;
        for (Eigen::Index i = begin; i < end; ++i) {
          block_row_product(A, static_cast<int>(i), x.data(), y.data() + 3 * i);
          sum += x[3 * i] * y[3 * i] + x[3 * i + 1] * y[3 * i + 1] + x[3 * i + 2] * y[3 * i + 2];
        }
        return sum;
      });
    };
  }
  return conjugate_gradient(cg.op, cg.preconditioner, b, cg.settings, stats_);
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
    throw std::invalid_argument("MultigridSolver::prolongation: level " + std::to_string(level) + " is the coarsest");
  }
  return fine.to_coarse->prolongation(fine.decoupled);
}

}  // namespace msfab
