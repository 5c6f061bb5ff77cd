#include "topopt/topology_optimizers.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <limits>

#include "core/errors.hpp"
#include "core/timing.hpp"

namespace msfab {

namespace {}  // namespace

VecX cell_gamut_conditions(const CellMaterialModel& model, const VecX& p, MatX* jacobian) {
  if (!model.has_constraint()) return VecX();
  const int m = 1 + model.bound_conditions();
  VecX c(m), grad;
  c[0] = model.constraint(p, jacobian ? &grad : nullptr);
  MatX bound_jac;
  if (m > 1) c.tail(m - 1) = model.bound_constraints(p, jacobian ? &bound_jac : nullptr);
  if (jacobian) {
    jacobian->resize(m, p.size());
    jacobian->row(0) = grad.transpose();
    if (m > 1) jacobian->bottomRows(m - 1) = bound_jac;
  }
  return c;
}

double max_gamut_violation(const CellMaterialModel& model, const MatX& p) {
  if (!model.has_constraint()) return -1.0;
  double worst = -std::numeric_limits<double>::infinity();
  for (Eigen::Index r = 0; r < p.rows(); ++r)
    worst = std::max(worst, cell_gamut_conditions(model, p.row(r).transpose(), nullptr).maxCoeff());
  return worst;
}

OptimizationResult optimize_oc(TopologyObjective& objective, const MatX& q0, const OptimizerSettings& settings) {
  if (q0.cols() != 1) throw InputError("the optimality-criteria update needs a one-parameter (simp) space");
  if (!settings.mass_limit) throw InputError("the optimality-criteria update needs a volume budget");
  OptimizationResult result;
  const auto t0 = std::chrono::steady_clock::now();
  const double V = objective.grid().cell_volume();
  const MatX ones = MatX::Ones(q0.rows(), 1);
  const VecX dmass = objective.filter().apply_transpose(ones).col(0) * V;  // d mass / dx
  VecX x = q0.col(0);
  for (int it = 1; it <= settings.max_iterations; ++it) {
    MatX g;
    const ObjectiveValue v = objective.evaluate(x, &g);
    ++result.evaluations;
    const VecX dc = g.col(0);
    // Bisection on the multiplier of the mass budget.
    double l1 = 0, l2 = 1e9;
    VecX x_new(x.size());
    while ((l2 - l1) / (l1 + l2) > 1e-3) {
      const double mid = 0.5 * (l1 + l2);
      for (Eigen::Index i = 0; i < x.size(); ++i) {
        const double be = std::sqrt(std::max(0.0, -dc[i] / (dmass[i] * mid)));
        x_new[i] =
            std::clamp(x[i] * be, std::max(0.0, x[i] - settings.oc_move), std::min(1.0, x[i] + settings.oc_move));
      }
      if (objective.mass(x_new) > settings.mass_budget)
        l1 = mid;
      else
        l2 = mid;
    }
    const double change = (x_new - x).cwiseAbs().maxCoeff();
    x = x_new;
    DesignHistoryEntry h{it - 1, v.total, v.elastic, 0.0, seconds_since(t0)};
    result.history.push_back(h);
    if (settings.log_every > 0 && (it - 1) % settings.log_every == 0)
      spdlog::info("oc iteration {:4d}: compliance {:.6e}  change {:.3f}  ({:.1f} s)", it - 1, v.elastic, change,
                   h.seconds);
    result.iterations = it;
    if (change < settings.change_tolerance) {
      result.converged = true;
      break;
    }
  }
  result.status = result.converged ? "converged (max change below tolerance)" : "iteration limit reached";
  result.q = x;
  result.value = objective.evaluate(result.q, nullptr);
  result.max_violation = (objective.mass(result.q) - settings.mass_budget) / (V * objective.grid().cells());
  result.seconds = seconds_since(t0);
  return result;
}

}  // namespace msfab
