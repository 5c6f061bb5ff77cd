#include "topopt/cell_mma.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <limits>
#include <string>

#include "core/errors.hpp"
#include "core/timing.hpp"
#include "topopt/cell_mma_subproblem.hpp"

namespace msfab {

namespace {

// Svanberg's constants (mmasub, 2007): the first asymptotes at half the
// box, their widening / narrowing by the sign pattern of the last moves,
// the move limit's distance from the asymptotes, and the term that keeps
// every approximation strictly convex.
constexpr double kAsymptoteInit = 0.5, kAsymptoteIncrease = 1.2, kAsymptoteDecrease = 0.7;
constexpr double kAsymptoteMin = 0.01, kAsymptoteMax = 10.0;
constexpr double kAlbefa = 0.1;
constexpr double kRaa0 = 1e-5;
// The price of the artificial slack of a cell constraint, against an
// objective scaled to a largest gradient entry of 1: multipliers of the
// gamut constraints are then O(1)-O(100), so a cell pays for the slack
// only where it cannot meet its constraints within the move limits.
constexpr double kSlackPrice = 1e4;
// Per-cell dual: projected gradient in the constraints' normalized units.
constexpr double kDualTolerance = 1e-11;
// Budget search: the approximate mass meets the budget to this fraction.
constexpr double kBudgetTolerance = 1e-9;
constexpr int kBudgetSearches = 60;
// The objective-stall stop (the Ipopt path's "acceptable" test).
constexpr double kStallChange = 1e-4;
constexpr int kStallWindow = 5;
constexpr int kStepHalvings = 20;

// The cell constraints' approximations are made conservative as in GCMMA
// (Svanberg 2002): where a constraint at the subproblem's solution is
// above its approximation, the approximation's curvature term raa grows by
// what was missing at that point (plus 10%; GCMMA's cap of 10x per round
// is left out: the constraints' gradients span five decades, and from the
// base 1e-5 it took up to eight rounds) and the cell is solved again. This
// costs no FEM solve (the constraints are cheap) and keeps the iterates in the
// gamut where its boundary curves faster than MMA's approximation (the
// Voigt bound's hydrostatic condition grows as 1 / (1 - 2 nu)); the
// objective keeps plain MMA's approximation.
constexpr int kConservativeRounds = 8;
constexpr double kRaaDecay = 0.5;

struct CellState {
  CellMmaApproximation approx;
  CellMmaSolution solution;  // its multipliers start the next solve
  CellMmaConstraintVec raa;  // the cell constraints' curvature terms
};

}  // namespace

OptimizationResult optimize_cell_mma(TopologyObjective& objective, const MatX& x0, const OptimizerSettings& settings,
                                     const CellFilter& gradient_smoothing) {
  const CellMaterialModel& model = objective.model();
  const int m = model.has_constraint() ? 1 + model.bound_conditions() : 0;
  if (m > kCellMmaMaxConstraints || model.parameters() > kCellMmaMaxVariables)
    throw std::logic_error("cell MMA: a cell has more conditions or parameters than the subproblem's fixed sizes");
  // A density filter makes every cell's physical parameters a mix of its
  // neighbours' variables: fine for the objective and the mass, whose MMA
  // approximations are separable in the variables whatever they depend on,
  // but a per-cell constraint on filtered parameters would couple the cells.
  const bool filtered = !objective.filter().identity();
  if (filtered && m > 0)
    throw InputError("cell MMA: a density filter on the parameters needs a space without per-cell constraints "
                     "(simp, or family3d with rho derived from the family); this space smooths the gradient instead");
  if (filtered && !gradient_smoothing.identity())
    throw InputError("cell MMA: both a density filter and gradient smoothing; choose one");
  if (!(settings.mma_move > 0 && settings.mma_move <= 1)) throw InputError("cell MMA: the move limit must be in (0, 1]");
  if (!(settings.change_tolerance >= 0)) throw InputError("cell MMA: the change tolerance must be >= 0");
  const Eigen::Index N = x0.rows();
  const int d = int(x0.cols());
  if (d != model.parameters() || d > kCellMmaMaxVariables)
    throw InputError("cell MMA: " + std::to_string(d) + " columns for a space with " +
                     std::to_string(model.parameters()) + " parameters");
  const int rho = model.density_index();
  // The mass is the variables' own rho column unless the filter or the
  // model's derived density put it through other cells' variables.
  const bool mass_is_rho = !filtered && !model.derives_density();

  OptimizationResult result;
  const auto t0 = std::chrono::steady_clock::now();
  // The box: Poisson's ratios and moduli stay off the faces, where some
  // compliances are singular (as for Ipopt).
  CellMmaVec xmin(d), xmax(d);
  for (int k = 0; k < d; ++k) xmin[k] = k == rho ? 0.0 : 1e-3, xmax[k] = k == rho ? 1.0 : 1 - 1e-3;
  const CellMmaVec range = xmax - xmin;
  MatX x = x0;
  for (Eigen::Index i = 0; i < N; ++i)
    for (int k = 0; k < d; ++k) x(i, k) = std::clamp(x(i, k), xmin[k], xmax[k]);

  // The budget in cell volumes, less the forced-solid cells.
  const double V = objective.grid().cell_volume();
  const double domain = V * double(objective.grid().cells());
  double forced_mass = 0;  // as TopologyObjective::mass counts them
  for (CellRole r : objective.setup().roles) forced_mass += r == CellRole::solid ? 1.0 : 0.0;
  forced_mass *= V;
  const double budget_cells = settings.mass_limit ? (settings.mass_budget - forced_mass) / V : 0.0;
  if (settings.mass_limit && budget_cells <= 0)
    throw InputError("cell MMA: the mass budget leaves nothing for the design cells (forced-solid cells use it all)");

  MatX x_old1 = x, x_old2 = x, low(N, d), upp(N, d);
  std::vector<CellState> cells(static_cast<std::size_t>(N));
  double mu = 0, scale = 0;
  std::vector<double> objective_history;
  bool converged = false;
  std::string why;

  for (int it = 0;; ++it) {
    // 1. The objective and its gradient at the iterate.
    // A step can leave the space's stable region where the gamut's level
    // set, padded and extrapolated, allows it (an orthotropic cell with
    // nu_xy^2 >= Ex / Ey has no positive definite stiffness): the step is
    // then halved towards the last iterate, as a line search would.
    MatX g;
    ObjectiveValue v;
    for (int halving = 0;; ++halving) {
      try {
        v = objective.evaluate(x, &g);
        ++result.evaluations;
        if (!std::isfinite(v.total)) throw NumericalError("the objective is not finite");
        break;
      } catch (const NumericalError& e) {
        if (it == 0 || halving == kStepHalvings)
          throw NumericalError("cell MMA, iteration " + std::to_string(it) + ": " + e.what());
        spdlog::debug("cell MMA iteration {}: {}; step halved", it, e.what());
        x = 0.5 * (x + x_old1);
      }
    }
    // 2. The cells' constraints and their gradients.
    MatX cval(N, m), cjac(N * m, d);  // cell i's gradients: rows i m .. i m + m - 1
#pragma omp parallel for schedule(static)
    for (Eigen::Index i = 0; i < (m > 0 ? N : 0); ++i) {
      MatX jac;
      cval.row(i) = cell_gamut_conditions(model, x.row(i).transpose(), &jac).transpose();
      cjac.middleRows(i * m, m) = jac;
    }
    double violation = m > 0 ? cval.maxCoeff() : -1.0;
    if (settings.mass_limit)
      violation = std::max(violation, (objective.mass(x) - settings.mass_budget) / domain);
    result.history.push_back({it, v.total, v.elastic, violation, seconds_since(t0)});
    objective_history.push_back(v.total);
    result.iterations = it;
    if (!converged && it >= kStallWindow && violation <= settings.constraint_tolerance) {
      const double before = objective_history[std::size_t(it - kStallWindow)];
      if (std::abs(v.total - before) <= kStallChange * std::abs(v.total)) {
        converged = true;
        why = "converged (objective change below 1e-4 over 5 iterations)";
      }
    }
    if (converged || it == settings.max_iterations) break;

    // 3. The smoothed gradient, scaled once so that its largest entry is 1.
    MatX gs = gradient_smoothing.identity() ? g : gradient_smoothing.apply(g);
    if (it == 0) {
      const double largest = gs.cwiseAbs().maxCoeff();
      if (!(std::isfinite(largest) && largest > 0))
        throw NumericalError("cell MMA: the objective's gradient at the start is zero or not finite");
      scale = 1.0 / largest;
    }
    gs *= scale;

    // The MMA approximation of cell i's constraint c around x (its value
    // and gradient there), with the cell's curvature term raa_c.
    const auto build_constraint = [&](Eigen::Index i, int c) {
      CellMmaApproximation& a = cells[std::size_t(i)].approx;
      const CellMmaVec xi = x.row(i).transpose(), jc = cjac.row(i * m + c).transpose();
      CellMmaVec pc, qc;
      a.b[c] = mma_coefficients(xi, a.lower, a.upper, jc, cval(i, c), range, cells[std::size_t(i)].raa[c], pc, qc);
      a.p.row(c) = pc.transpose(), a.q.row(c) = qc.transpose();
    };

    // 4. Asymptotes and the cells' approximations. Each cell's share of
    //    the mass: its physical rho, with d mass / d (its variables).
    const auto tu = std::chrono::steady_clock::now();
    MatX cell_mass, cell_mass_gradient;
    if (settings.mass_limit && !mass_is_rho) {
      cell_mass = objective.physical(x).col(rho);
      cell_mass_gradient = objective.mass_gradient(x) / V;
    }
#pragma omp parallel for schedule(static)
    for (Eigen::Index i = 0; i < N; ++i) {
      CellMmaApproximation& a = cells[std::size_t(i)].approx;
      a.lower.resize(d), a.upper.resize(d), a.alpha.resize(d), a.beta.resize(d);
      CellMmaVec xi(d);
      for (int k = 0; k < d; ++k) {
        const double xk = x(i, k), r = range[k];
        double L, U;
        if (it < 2) {
          L = xk - kAsymptoteInit * r, U = xk + kAsymptoteInit * r;
        } else {
          const double pattern = (xk - x_old1(i, k)) * (x_old1(i, k) - x_old2(i, k));
          const double f = pattern > 0 ? kAsymptoteIncrease : pattern < 0 ? kAsymptoteDecrease : 1.0;
          L = xk - f * (x_old1(i, k) - low(i, k));
          U = xk + f * (upp(i, k) - x_old1(i, k));
          L = std::clamp(L, xk - kAsymptoteMax * r, xk - kAsymptoteMin * r);
          U = std::clamp(U, xk + kAsymptoteMin * r, xk + kAsymptoteMax * r);
        }
        low(i, k) = L, upp(i, k) = U;
        a.lower[k] = L, a.upper[k] = U;
        a.alpha[k] = std::max({xmin[k], L + kAlbefa * (xk - L), xk - settings.mma_move * r});
        a.beta[k] = std::min({xmax[k], U - kAlbefa * (U - xk), xk + settings.mma_move * r});
        xi[k] = xk;
      }
      const CellMmaVec gi = gs.row(i).transpose();
      mma_coefficients(xi, a.lower, a.upper, gi, 0.0, range, kRaa0, a.p0, a.q0);
      a.p.resize(m, d), a.q.resize(m, d), a.b.resize(m);
      CellMmaConstraintVec& raa = cells[std::size_t(i)].raa;
      if (raa.size() != m) raa = CellMmaConstraintVec::Constant(m, kRaa0);
      for (int c = 0; c < m; ++c) {
        raa[c] = std::max(kRaa0, kRaaDecay * raa[c]);
        build_constraint(i, c);
      }
      if (settings.mass_limit && !mass_is_rho) {
        const CellMmaVec e = cell_mass_gradient.row(i).transpose();
        a.bm = mma_coefficients(xi, a.lower, a.upper, e, cell_mass(i, 0), range, kRaa0, a.pm, a.qm);
      } else if (settings.mass_limit) {
        CellMmaVec e = CellMmaVec::Zero(d);
        e[rho] = 1.0;
        a.bm = mma_coefficients(xi, a.lower, a.upper, e, xi[rho], range, kRaa0, a.pm, a.qm);
      } else {
        a.pm = CellMmaVec::Zero(d), a.qm = CellMmaVec::Zero(d), a.bm = 0;
      }
    }

    // 5. The subproblem: every cell's dual at the budget's multiplier mu,
    //    and a safeguarded Newton search on mu (the approximate mass falls
    //    as mu grows).
    int searches = 0;
    const auto solve_all = [&](double at, double& mass, double& slope) {
      ++searches;
#pragma omp parallel for schedule(dynamic, 256)
      for (Eigen::Index i = 0; i < N; ++i) {
        CellState& s = cells[std::size_t(i)];
        s.solution = solve_cell_mma(s.approx, at, s.solution.lambda, kSlackPrice, kDualTolerance);
      }
      mass = 0, slope = 0;  // summed in cell order: the same for any thread count
      for (const CellState& s : cells) mass += s.solution.mass, slope += s.solution.mass_derivative;
    };
    double mass = 0, slope = 0;
    const auto budget_search = [&] {
      if (!settings.mass_limit) {
        mu = 0;
        solve_all(0.0, mass, slope);
      } else {
        // From the last multiplier (the budget's price moves little from one
        // iteration to the next) unless that was the slack price; Newton
        // steps inside a bracket, decades while there is no upper end.
        double at = mu > 0 && mu < kSlackPrice ? mu : 0.0;
        double lo = 0, hi = std::numeric_limits<double>::infinity();
        bool capped = false;
        for (int s = 0; s < kBudgetSearches; ++s) {
          solve_all(at, mass, slope);
          const double excess = mass - budget_cells;
          spdlog::debug("budget search {}: mu {:.10e} excess {:.3e} slope {:.3e} bracket [{:.6e}, {:.6e}]", s, at,
                        excess / budget_cells, slope, lo, hi);
          if (excess <= kBudgetTolerance * budget_cells && (at == 0 || excess >= -kBudgetTolerance * budget_cells))
            break;
          if (excess > 0) lo = at; else hi = at;
          if (std::isfinite(hi) && hi - lo <= 1e-14 * hi) break;
          double next = slope < 0 ? at - excess / slope : std::numeric_limits<double>::quiet_NaN();
          if (!(next > lo && next < hi))
            next = !std::isfinite(hi) ? 10 * std::max(at, 1e-6) : lo > 0 ? std::sqrt(lo * hi) : 0.1 * hi;
          // Until the budget is bracketed, at most a decade per search: where
          // the mass hardly responds to mu (a parameter the objective does not
          // see, such as a family cell's rho above its member's), Newton's
          // step from the slope jumps straight to the slack price, and every
          // cell sheds all the mass its move limits allow.
          if (!std::isfinite(hi)) next = std::min(next, 10 * std::max(at, 1e-6));
          if (!std::isfinite(hi) && next >= kSlackPrice) {
            // The move limits cannot shed enough mass in one step (a start
            // above the budget): the budget gets the cells' slack price,
            // and the excess is shed over the next iterations.
            at = kSlackPrice;
            solve_all(at, mass, slope);
            capped = true;
            break;
          }
          at = next;
        }
        if (!capped && mass - budget_cells > kBudgetTolerance * budget_cells && std::isfinite(hi)) {
          at = hi;  // the feasible end of the bracket
          solve_all(at, mass, slope);
        }
        mu = at;
      }
    };
    budget_search();
    // Conservative? The cells whose true constraints are violated at the
    // solution and above their approximations get more curvature (GCMMA's
    // rule; an approximation that is low where the constraint holds to 1%
    // of the constraint tolerance is left alone) and are solved again at
    // the same mu; the budget is searched again at the end.
    const double violation_floor = 0.01 * settings.constraint_tolerance;
    std::vector<char> raised(std::size_t(N), 0), check(std::size_t(N), 1);
    int conservative_rounds = 0;
    for (; m > 0 && conservative_rounds < kConservativeRounds; ++conservative_rounds) {
      std::fill(raised.begin(), raised.end(), 0);
#pragma omp parallel for schedule(dynamic, 256)
      for (Eigen::Index i = 0; i < N; ++i) {
        if (!check[std::size_t(i)]) continue;
        CellState& st = cells[std::size_t(i)];
        const CellMmaApproximation& a = st.approx;
        const CellMmaVec& xn = st.solution.x;
        // A cell on its slack cannot meet its constraints within the move
        // limits (a start outside the gamut); more curvature would not help.
        if (st.solution.slack > 0) continue;
        double distance = 0;
        for (int k = 0; k < d; ++k) {
          const double dx = xn[k] - x(i, k);
          distance += (a.upper[k] - a.lower[k]) * dx * dx /
                      ((a.upper[k] - xn[k]) * (xn[k] - a.lower[k]) * range[k]);
        }
        if (!(distance > 0)) continue;
        const VecX values = cell_gamut_conditions(model, VecX(xn), nullptr);
        for (int c = 0; c < m; ++c) {
          double approx = -a.b[c];
          for (int k = 0; k < d; ++k) approx += a.p(c, k) / (a.upper[k] - xn[k]) + a.q(c, k) / (xn[k] - a.lower[k]);
          if (values[c] <= violation_floor || values[c] <= approx) continue;
          st.raa[c] = 1.1 * (st.raa[c] + (values[c] - approx) / distance);
          build_constraint(i, c);
          raised[std::size_t(i)] = 1;
        }
        if (raised[std::size_t(i)]) {
          st.solution = solve_cell_mma(st.approx, mu, st.solution.lambda, kSlackPrice, kDualTolerance);
        }
      }
      long count = 0;
      for (char r : raised) count += r;
      if (count == 0) break;
      spdlog::debug("cell MMA iteration {}: round {}: {} cells not conservative", it, conservative_rounds, count);
      check = raised;
    }
    if (conservative_rounds > 0 && settings.mass_limit) {
      mass = 0;
      for (const CellState& st : cells) mass += st.solution.mass;
      if (std::abs(mass - budget_cells) > kBudgetTolerance * budget_cells) budget_search();
    }

    // 6. The update.
    MatX x_new(N, d);
    double slack = 0;
    int unconverged = 0;
    for (Eigen::Index i = 0; i < N; ++i) {
      const CellMmaSolution& s = cells[std::size_t(i)].solution;
      x_new.row(i) = s.x.transpose();
      slack = std::max(slack, s.slack);
      unconverged += s.converged ? 0 : 1;
    }
    if (unconverged > 0) spdlog::debug("cell MMA iteration {}: {} cell duals above tolerance", it, unconverged);
    const double change = (x_new - x).cwiseAbs().maxCoeff();
    x_old2 = x_old1;
    x_old1 = x;
    x = x_new;
    result.update_seconds += seconds_since(tu);
    if (settings.log_every > 0 && it % settings.log_every == 0)
      spdlog::info("cell-mma iteration {:4d}: S {:.6e}  elastic {:.6e}  max constraint {:.2e}  change {:.3f}  "
                   "budget searches {}, conservative rounds {}  ({:.1f} s, subproblem {:.2f} s)",
                   it, v.total, v.elastic, violation, change, searches, conservative_rounds, seconds_since(t0),
                   seconds_since(tu));
    if (m > 0 && spdlog::should_log(spdlog::level::debug)) {
      // Which cell holds the largest violation, where, and what its
      // multipliers became: the first thing to look at when a run stalls.
      Eigen::Index wi, wc;
      cval.maxCoeff(&wi, &wc);
      std::string at, multipliers;
      for (int k = 0; k < d; ++k) at += fmt::format(" {:.4f}", x_old1(wi, k));
      for (int c = 0; c < m; ++c) multipliers += fmt::format(" {:.3e}", cells[std::size_t(wi)].solution.lambda[c]);
      spdlog::debug("cell MMA iteration {}: worst cell {} condition {} value {:.3e} at [{} ], multipliers [{} ]", it,
                    wi, wc, cval(wi, wc), at, multipliers);
    }
    if (slack > 0) spdlog::debug("cell MMA iteration {}: largest artificial slack {:.2e}", it, slack);
    if (change < settings.change_tolerance) {
      converged = true;
      why = "converged (max change below tolerance)";
    }
  }
  result.status = converged ? why : "iteration limit reached";
  result.converged = converged;
  result.q = x;
  result.value = objective.evaluate(x, nullptr);  // the cached state: no solve
  result.max_violation = result.history.back().max_violation;
  result.seconds = seconds_since(t0);
  return result;
}

}  // namespace msfab
