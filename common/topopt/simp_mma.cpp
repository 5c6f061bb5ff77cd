#include "topopt/simp_mma.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <nlopt.hpp>

#include "core/errors.hpp"
#include "core/timing.hpp"

namespace msfab {

namespace {

// Volume excess accepted as feasible, in cell volumes. MMA's approximation
// of a linear constraint is conservative, so feasible iterates stay feasible
// up to the dual solver's round-off.
constexpr double kVolumeTolerance = 1e-6;

// NLopt's rho (the curvature that keeps the approximation conservative)
// starts at 1 and never drops below 1e-5 in absolute terms, so the scale of
// the objective sets how bold the first steps are and how far MMA can
// relax later. Starting it at 100 (Svanberg's advice: between 1 and 100)
// gave the lowest compliance after 40 iterations on the 3D cantilever
// among 1, 10, 100, 1000 and the number of cells (64x32x32; at 128x64x64
// 100 beat the number of cells by 17%); on the 2D MBB beam its final
// compliance was the lowest of them and within 1% of the best after 40
// iterations (docs/topopt.md).
constexpr double kObjectiveStart = 100.0;

struct MmaProblem {
  TopologyObjective* objective = nullptr;
  const OptimizerSettings* settings = nullptr;
  OptimizationResult* result = nullptr;
  nlopt::opt* opt = nullptr;
  std::chrono::steady_clock::time_point t0;
  VecX dmass;             // d mass / dq: the filter's column sums times the cell volume
  double fixed_mass = 0;  // forced-solid cells
  double cell_volume = 1, domain_volume = 1;
  double objective_scale = 1;  // kObjectiveStart / S(q0)
  // The incumbent: the best feasible design evaluated so far (or, before
  // any is feasible, the least infeasible). With a feasible start this is
  // MMA's own iterate: once feasible, NLopt keeps a trial point when it
  // lowers the objective and stays feasible (up to the dual's round-off),
  // and otherwise tries again closer in (an inner iteration). The history
  // and the result follow the incumbent, so a rejected trial costs a solve
  // but never shows as a rise.
  bool have_best = false, best_feasible = false;
  VecX best_q;
  ObjectiveValue best_value;
  double best_excess = 0;
  long long cg_before = 0;
  int solves_before = 0;
  std::exception_ptr error;

  double mass(const double* q) const { return Eigen::Map<const VecX>(q, dmass.size()).dot(dmass) + fixed_mass; }
};

double mma_objective(unsigned n, const double* q, double* grad, void* data) {
  auto& P = *static_cast<MmaProblem*>(data);
  try {
    const Eigen::Map<const VecX> x(q, n);
    MatX g;
    const ObjectiveValue v = P.objective->evaluate(MatX(x), grad ? &g : nullptr);
    OptimizationResult& r = *P.result;
    const int it = r.evaluations++;
    if (it == 0) {
      if (!(std::isfinite(v.total) && v.total > 0))
        throw NumericalError("MMA: the objective at the start is " + std::to_string(v.total) +
                             "; it must be positive and finite to scale the problem");
      P.objective_scale = kObjectiveStart / v.total;
    }
    // The step tried from the incumbent.
    const double change = P.have_best ? (x - P.best_q).cwiseAbs().maxCoeff() : 0.0;
    const double excess = (P.mass(q) - P.settings->mass_budget) / P.domain_volume;
    const bool feasible = (P.mass(q) - P.settings->mass_budget) / P.cell_volume <= kVolumeTolerance;
    const bool better = !P.have_best || (feasible ? !P.best_feasible || v.total < P.best_value.total
                                                  : !P.best_feasible && excess < P.best_excess);
    if (better) {
      P.have_best = true, P.best_feasible = feasible;
      P.best_q = x, P.best_value = v, P.best_excess = excess;
    } else {
      spdlog::debug("mma evaluation {}: trial rejected (objective {:.6e}, volume excess {:.2e})", it, v.total, excess);
    }
    const DesignHistoryEntry h{it, P.best_value.total, P.best_value.elastic, P.best_excess, seconds_since(P.t0)};
    r.history.push_back(h);
    const GridSolveStats& st = P.objective->elasticity().stats();
    if (P.settings->log_every > 0 && it % P.settings->log_every == 0) {
      const int solves = st.solves - P.solves_before;
      const double cg = solves > 0 ? double(st.iterations - P.cg_before) / solves : 0.0;
      spdlog::info("mma iteration {:4d}: objective {:.6e}  volume {:.4f}  step {:.3f}  CG/solve {:.1f}  ({:.1f} s)", it,
                   h.objective, P.best_excess + P.settings->mass_budget / P.domain_volume, change, cg, h.seconds);
      P.cg_before = st.iterations, P.solves_before = st.solves;
    }
    if (grad) Eigen::Map<VecX>(grad, n) = g.col(0) * P.objective_scale;
    return v.total * P.objective_scale;
  } catch (...) {
    // NLopt's C++ wrapper would turn the exception into a bare failure code;
    // keep it and rethrow it after optimize() returns.
    P.error = std::current_exception();
    P.opt->force_stop();
    return std::numeric_limits<double>::quiet_NaN();
  }
}

double mma_volume(unsigned n, const double* q, double* grad, void* data) {
  const auto& P = *static_cast<const MmaProblem*>(data);
  if (grad) Eigen::Map<VecX>(grad, n) = P.dmass / P.cell_volume;
  return (P.mass(q) - P.settings->mass_budget) / P.cell_volume;
}

}  // namespace

OptimizationResult optimize_mma(TopologyObjective& objective, const MatX& q0, const OptimizerSettings& settings) {
  if (q0.cols() != 1 || objective.model().parameters() != 1)
    throw InputError("MMA is for the simp spaces (simp2d, simp3d): one density per cell");
  if (!settings.mass_limit) throw InputError("MMA on a simp space needs a volume budget (mass.volume_fraction)");
  if (!(settings.change_tolerance >= 0)) throw InputError("MMA: the change tolerance must be >= 0");
  const Eigen::Index n = q0.rows();
  OptimizationResult result;
  MmaProblem P;
  P.objective = &objective;
  P.settings = &settings;
  P.result = &result;
  P.t0 = std::chrono::steady_clock::now();
  P.cell_volume = objective.grid().cell_volume();
  P.domain_volume = P.cell_volume * double(objective.grid().cells());
  P.dmass = objective.filter().apply_transpose(MatX::Ones(n, 1)).col(0) * P.cell_volume;
  P.fixed_mass = objective.mass(MatX::Zero(n, 1));
  const GridSolveStats& st = objective.elasticity().stats();
  P.cg_before = st.iterations, P.solves_before = st.solves;

  nlopt::opt opt(nlopt::LD_MMA, unsigned(n));
  P.opt = &opt;
  opt.set_lower_bounds(0.0);
  opt.set_upper_bounds(1.0);
  opt.set_min_objective(mma_objective, &P);
  opt.add_inequality_constraint(mma_volume, &P, kVolumeTolerance);
  opt.set_maxeval(settings.max_iterations + 1);
  if (settings.change_tolerance > 0) opt.set_xtol_abs(settings.change_tolerance);

  std::vector<double> x(q0.data(), q0.data() + n);
  double f = 0;
  nlopt::result code = nlopt::FAILURE;
  try {
    code = opt.optimize(x, f);
  } catch (const nlopt::roundoff_limited&) {
    code = nlopt::ROUNDOFF_LIMITED;
  } catch (const nlopt::forced_stop&) {
    if (P.error) std::rethrow_exception(P.error);
    throw;
  } catch (const std::runtime_error& e) {
    if (P.error) std::rethrow_exception(P.error);
    throw NumericalError(std::string("MMA failed: ") + e.what());
  }
  if (P.error) std::rethrow_exception(P.error);
  switch (code) {
    case nlopt::XTOL_REACHED: result.status = "converged (max change below tolerance)", result.converged = true; break;
    case nlopt::MAXEVAL_REACHED: result.status = "iteration limit reached"; break;
    case nlopt::ROUNDOFF_LIMITED: result.status = "stopped by round-off (best iterate kept)"; break;
    default: result.status = "nlopt result " + std::to_string(int(code)), result.converged = code > 0; break;
  }
  if (!P.have_best) throw NumericalError("MMA stopped before its first evaluation: " + result.status);
  result.q = P.best_q;
  result.iterations = std::max(0, result.evaluations - 1);
  result.value = P.best_value;
  result.max_violation = P.best_excess;
  result.seconds = seconds_since(P.t0);
  return result;
}

}  // namespace msfab
