// Problem 3.5 with Ipopt. Built as its own library (msfab_ipopt): the
// Debian Ipopt links the sequential MUMPS, whose stand-in MPI symbols clash
// with Open MPI in the MPI stages, so only the stages that optimize link it.
#include <omp.h>
#include <spdlog/spdlog.h>

#include <IpIpoptApplication.hpp>
#include <IpTNLP.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>

#include "core/errors.hpp"
#include "core/timing.hpp"
#include "solve/blas_threads.hpp"
#include "topopt/topology_optimizers.hpp"

namespace msfab {

namespace {

using Ipopt::Index;
using Ipopt::Number;

// MUMPS orders some of these KKT systems with SCOTCH (its automatic choice
// for the 2D grippers), and SCOTCH 7 on several threads orders the same
// matrix differently from run to run: one run in 20 to 60 then took
// another first step and ended at another design (docs/topopt.md,
// "Determinism"). On one thread its ordering is the same every time, and
// it was faster on two cores. SCOTCH reads this variable whenever MUMPS
// asks it for an ordering.
void single_threaded_scotch() { setenv("SCOTCH_PTHREAD_NUMBER", "1", 1); }

// Problem 3.5 for Ipopt. Variables x[r d + k] = q(r, k); constraints: per
// design cell (when the space has a constraint) Phi and the Voigt bound's
// conditions (rows r * per_cell_ + c), then the mass budget
// (when asked for), scaled to a volume fraction.
class GamutProblem : public Ipopt::TNLP {
 public:
  GamutProblem(TopologyObjective& objective, const MatX& q0, const OptimizerSettings& settings,
               OptimizationResult& result)
      : obj_(objective),
        model_(objective.model()),
        q0_(q0),
        settings_(settings),
        result_(result),
        rows_(q0.rows()),
        d_(q0.cols()),
        threads_(omp_get_max_threads()),
        t0_(std::chrono::steady_clock::now()) {
    per_cell_ = model_.has_constraint() ? 1 + model_.bound_conditions() : 0;
    gamut_rows_ = per_cell_ * rows_;
    const double V = obj_.grid().cell_volume();
    volume_ = V * double(obj_.grid().cells());
    if (settings.mass_limit) {
      // d(mass)/dq_{j, rho} = V sum_r H_rj (column sums of the filter).
      const MatX ones = MatX::Ones(rows_, 1);
      mass_gradient_ = obj_.filter().apply_transpose(ones).col(0) * (V / volume_);
    }
    const ObjectiveValue v0 = obj_.evaluate(q0_, nullptr);
    scale_ = std::abs(v0.total) > 0 ? 1.0 / std::abs(v0.total) : 1.0;
  }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac, Index& nnz_h, IndexStyleEnum& style) override {
    n = Index(rows_ * d_);
    m = Index(gamut_rows_ + (settings_.mass_limit ? 1 : 0));
    const auto& H = obj_.filter().weights();
    const Eigen::Index per_row = obj_.filter().identity() ? 1 : 0;
    nnz_jac = Index(gamut_rows_ * d_ * per_row + (per_row ? 0 : per_cell_ * H.nonZeros() * d_) +
                    (settings_.mass_limit ? rows_ : 0));
    nnz_h = 0;
    style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l, Number* g_u) override {
    const int rho = model_.density_index();
    for (Index i = 0; i < n; ++i) {
      // Poisson's ratios and moduli stay off the box's faces, where some
      // compliances are singular (nu = -1, nu = 1/2 in 3D).
      const bool is_rho = int(i % d_) == rho;
      x_l[i] = is_rho ? 0.0 : 1e-3;
      x_u[i] = is_rho ? 1.0 : 1 - 1e-3;
    }
    for (Index j = 0; j < m; ++j) g_l[j] = -2e19, g_u[j] = 0.0;
    if (settings_.mass_limit) g_u[m - 1] = settings_.mass_budget / volume_;
    return true;
  }

  bool get_starting_point(Index n, bool init_x, Number* x, bool, Number*, Number*, Index, bool, Number*) override {
    if (!init_x) return false;
    for (Index i = 0; i < n; ++i) x[i] = q0_(i / d_, i % d_);
    return true;
  }

  bool eval_f(Index n, const Number* x, bool, Number& f) override {
    const OmpThreads threads(threads_);
    try {
      f = scale_ * obj_.evaluate(as_q(n, x), nullptr).total;
      ++result_.evaluations;
      return std::isfinite(f);
    } catch (const NumericalError& e) {
      spdlog::debug("objective evaluation failed: {}", e.what());
      return false;  // Ipopt cuts the step back
    }
  }

  bool eval_grad_f(Index n, const Number* x, bool, Number* grad) override {
    const OmpThreads threads(threads_);
    try {
      MatX g;
      obj_.evaluate(as_q(n, x), &g);
      for (Index i = 0; i < n; ++i) grad[i] = scale_ * g(i / d_, i % d_);
      return true;
    } catch (const NumericalError& e) {
      spdlog::debug("gradient evaluation failed: {}", e.what());
      return false;
    }
  }

  bool eval_g(Index n, const Number* x, bool, Index m, Number* g) override {
    if (per_cell_ > 0) {
      const MatX p = obj_.physical(as_q(n, x));
      for (Eigen::Index r = 0; r < rows_; ++r) {
        const VecX c = cell_constraints(p.row(r).transpose(), nullptr);
        for (Eigen::Index i = 0; i < per_cell_; ++i) g[r * per_cell_ + i] = c[i];
      }
    }
    if (settings_.mass_limit) g[m - 1] = obj_.mass(as_q(n, x)) / volume_;
    return true;
  }

  bool eval_jac_g(Index n, const Number* x, bool, Index, Index, Index* iRow, Index* jCol, Number* values) override {
    const auto& H = obj_.filter().weights();
    const bool identity = obj_.filter().identity();
    Index e = 0;
    if (!values) {
      for (Eigen::Index row = 0; row < gamut_rows_; ++row) {
        const Eigen::Index r = row / per_cell_;
        if (identity) {
          for (Eigen::Index k = 0; k < d_; ++k) iRow[e] = Index(row), jCol[e] = Index(r * d_ + k), ++e;
        } else {
          for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(H, r); it; ++it)
            for (Eigen::Index k = 0; k < d_; ++k) iRow[e] = Index(row), jCol[e] = Index(it.col() * d_ + k), ++e;
        }
      }
      if (settings_.mass_limit)
        for (Eigen::Index j = 0; j < rows_; ++j)
          iRow[e] = Index(gamut_rows_), jCol[e] = Index(j * d_ + model_.density_index()), ++e;
      return true;
    }
    const MatX p = per_cell_ > 0 ? obj_.physical(as_q(n, x)) : MatX();
    MatX jac;
    for (Eigen::Index r = 0; per_cell_ > 0 && r < rows_; ++r) {
      cell_constraints(p.row(r).transpose(), &jac);
      for (Eigen::Index i = 0; i < per_cell_; ++i) {
        if (identity) {
          for (Eigen::Index k = 0; k < d_; ++k) values[e++] = jac(i, k);
        } else {
          for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(H, r); it; ++it)
            for (Eigen::Index k = 0; k < d_; ++k) values[e++] = jac(i, k) * it.value();
        }
      }
    }
    if (settings_.mass_limit)
      for (Eigen::Index j = 0; j < rows_; ++j) values[e++] = mass_gradient_[j];
    return true;
  }

  bool intermediate_callback(Ipopt::AlgorithmMode, Index iter, Number obj_value, Number inf_pr, Number, Number, Number,
                             Number, Number, Number, Index, const Ipopt::IpoptData*,
                             Ipopt::IpoptCalculatedQuantities*) override {
    DesignHistoryEntry h;
    h.iteration = iter;
    h.objective = obj_value / scale_;
    // The last evaluation is the accepted iterate's (Ipopt evaluates the
    // trial point it accepts last).
    h.elastic = last_elastic();
    h.max_violation = inf_pr;
    h.seconds = seconds_since(t0_);
    result_.history.push_back(h);
    if (settings_.log_every > 0 && iter % settings_.log_every == 0)
      spdlog::info("ipopt iteration {:4d}: S {:.6e}  elastic {:.6e}  constraint violation {:.2e}  ({:.1f} s)", iter,
                   h.objective, h.elastic, inf_pr, h.seconds);
    return true;
  }

  void finalize_solution(Ipopt::SolverReturn, Index n, const Number* x, const Number*, const Number*, Index,
                         const Number*, const Number*, Number, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    result_.q = as_q(n, x);
  }

 private:
  // Phi and the Voigt bound's conditions of one cell at physical p.
  VecX cell_constraints(const VecX& p, MatX* jacobian) const { return cell_gamut_conditions(model_, p, jacobian); }
  MatX as_q(Index n, const Number* x) const {
    MatX q(rows_, d_);
    for (Index i = 0; i < n; ++i) q(i / d_, i % d_) = x[i];
    return q;
  }
  double last_elastic() {
    // evaluate() returns the cached state without new solves.
    return obj_.last_value().elastic;
  }

  TopologyObjective& obj_;
  const CellMaterialModel& model_;
  MatX q0_;
  const OptimizerSettings& settings_;
  OptimizationResult& result_;
  Eigen::Index rows_, d_, per_cell_ = 0, gamut_rows_ = 0;
  int threads_;  // the caller's, for the objective inside Ipopt's one-thread scope
  double scale_ = 1, volume_ = 1;
  VecX mass_gradient_;
  std::chrono::steady_clock::time_point t0_;
};

}  // namespace

OptimizationResult optimize_in_gamut(TopologyObjective& objective, const MatX& q0, const OptimizerSettings& settings) {
  // The mass constraint below is linear in q (the filter's column sums).
  if (objective.model().derives_density())
    throw InputError("ipopt: a space whose rho is derived from its other parameters is optimized by cell-mma only");
  single_threaded_scotch();
  OptimizationResult result;
  const auto t0 = std::chrono::steady_clock::now();
  Ipopt::SmartPtr<Ipopt::TNLP> problem = new GamutProblem(objective, q0, settings, result);
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  app->Options()->SetIntegerValue("print_level", 0);
  app->Options()->SetStringValue("sb", "yes");
  app->Options()->SetStringValue("hessian_approximation", "limited-memory");
  app->Options()->SetIntegerValue("limited_memory_max_history", settings.lbfgs_memory);
  app->Options()->SetIntegerValue("max_iter", settings.max_iterations);
  app->Options()->SetNumericValue("tol", settings.tolerance);
  app->Options()->SetNumericValue("acceptable_tol", 10 * settings.tolerance);
  app->Options()->SetNumericValue("constr_viol_tol", settings.constraint_tolerance);
  app->Options()->SetStringValue("mu_strategy", "adaptive");
  // The cells are held to the level set's quadratic B-spline, which is C1
  // but whose curvature jumps across grid faces, so the dual infeasibility
  // can stall above tight tolerances while the objective settles. Then stop
  // when the objective has changed by less than 1e-4 (relative to the
  // start) for 5 iterations with the constraints met to
  // constraint_tolerance (docs/topopt.md).
  app->Options()->SetIntegerValue("acceptable_iter", 5);
  app->Options()->SetNumericValue("acceptable_obj_change_tol", 1e-4);
  app->Options()->SetNumericValue("acceptable_constr_viol_tol", settings.constraint_tolerance);
  app->Options()->SetNumericValue("acceptable_dual_inf_tol", 1e10);
  app->Options()->SetNumericValue("acceptable_compl_inf_tol", 1e-2);
  if (app->Initialize() != Ipopt::Solve_Succeeded) throw std::runtime_error("Ipopt failed to initialize");
  // MUMPS factorizes Ipopt's KKT system with OpenMP and BLAS threads of its
  // own, which on two cores shared with the FEM cost more than they gain
  // (a 20-iteration cantilever run: 4x faster on one thread under load;
  // solve/blas_threads.hpp). The objective's callbacks get the caller's
  // threads back (OmpThreads).
  const Ipopt::ApplicationReturnStatus status = [&] {
    const OmpThreads one(1);
    const SingleThreadedBlas blas;
    return app->OptimizeTNLP(problem);
  }();
  switch (status) {
    case Ipopt::Solve_Succeeded: result.status = "converged", result.converged = true; break;
    case Ipopt::Solved_To_Acceptable_Level:
      result.status = "converged to the acceptable level", result.converged = true;
      break;
    case Ipopt::Maximum_Iterations_Exceeded: result.status = "iteration limit reached"; break;
    case Ipopt::Search_Direction_Becomes_Too_Small: result.status = "search direction too small"; break;
    case Ipopt::Restoration_Failed: result.status = "restoration phase failed"; break;
    case Ipopt::Error_In_Step_Computation: result.status = "error in step computation"; break;
    case Ipopt::Infeasible_Problem_Detected: result.status = "locally infeasible"; break;
    default: result.status = "ipopt status " + std::to_string(int(status)); break;
  }
  if (result.q.size() == 0) throw NumericalError("Ipopt stopped without a solution: " + result.status);
  result.iterations = result.history.empty() ? 0 : result.history.back().iteration;
  result.value = objective.evaluate(result.q, nullptr);
  const MatX p = objective.physical(result.q);
  result.max_violation = max_gamut_violation(objective.model(), p);
  if (settings.mass_limit)
    result.max_violation =
        std::max(result.max_violation, (objective.mass(result.q) - settings.mass_budget) /
                                           (objective.grid().cell_volume() * objective.grid().cells()));
  result.seconds = seconds_since(t0);
  return result;
}

}  // namespace msfab
