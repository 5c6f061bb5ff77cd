#include "topopt/cell_mma.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
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

// One cell-MMA run: the iterate with its two predecessors and asymptotes,
// every cell's approximation, and the steps of an iteration.
class CellMmaRun {
 public:
  CellMmaRun(TopologyObjective& objective, const MatX& x0, const OptimizerSettings& settings,
             const CellFilter& gradient_smoothing);
  OptimizationResult run();

 private:
  ObjectiveValue evaluate_with_halving(int it, MatX& g);
  // The cells' constraints (N x m) and their gradients (cell i's in rows
  // i m .. i m + m - 1).
  void cell_conditions(MatX& cval, MatX& cjac) const;
  // The MMA approximation of cell i's constraint c around x (its value and
  // gradient there), with the cell's curvature term raa_c.
  void build_constraint(Eigen::Index i, int c, const MatX& cval, const MatX& cjac);
  // Asymptotes and every cell's approximations of the objective (scaled
  // gradient gs), its constraints and its share of the mass.
  void build_approximations(int it, const MatX& gs, const MatX& cval, const MatX& cjac);
  // Every cell's dual at the budget's multiplier `at`; the approximate mass
  // and its derivative in mu, summed in cell order.
  void solve_all(double at, double& mass, double& slope);
  // mu for the budget: a safeguarded Newton search (the approximate mass
  // falls as mu grows).
  void budget_search(double& mass, double& slope);
  // GCMMA's conservative rounds; returns how many ran.
  int make_conservative(int it, const MatX& cval, const MatX& cjac);

  TopologyObjective& objective_;
  const OptimizerSettings& settings_;
  const CellFilter& gradient_smoothing_;
  const CellMaterialModel& model_;
  const int m_;
  Eigen::Index N_ = 0;
  int d_ = 0, rho_ = 0;
  bool mass_is_rho_ = true;
  double V_ = 0, domain_ = 0, budget_cells_ = 0;
  CellMmaVec xmin_, xmax_, range_;
  MatX x_, x_old1_, x_old2_, low_, upp_;
  std::vector<CellState> cells_;
  double mu_ = 0, scale_ = 0;
  int searches_ = 0;
  OptimizationResult result_;
  std::chrono::steady_clock::time_point t0_;
};

CellMmaRun::CellMmaRun(TopologyObjective& objective, const MatX& x0, const OptimizerSettings& settings,
                       const CellFilter& gradient_smoothing)
    : objective_(objective),
      settings_(settings),
      gradient_smoothing_(gradient_smoothing),
      model_(objective.model()),
      m_(model_.has_constraint() ? 1 + model_.bound_conditions() : 0) {
  if (m_ > kCellMmaMaxConstraints || model_.parameters() > kCellMmaMaxVariables)
    throw std::logic_error("cell MMA: a cell has more conditions or parameters than the subproblem's fixed sizes");
  // A density filter makes every cell's physical parameters a mix of its
  // neighbours' variables: fine for the objective and the mass, whose MMA
  // approximations are separable in the variables whatever they depend on,
  // but a per-cell constraint on filtered parameters would couple the cells.
  const bool filtered = !objective.filter().identity();
  if (filtered && m_ > 0)
    throw InputError(
        "cell MMA: a density filter on the parameters needs a space without per-cell constraints "
        "(simp, or family3d with rho derived from the family); this space smooths the gradient instead");
  if (filtered && !gradient_smoothing.identity())
    throw InputError("cell MMA: both a density filter and gradient smoothing; choose one");
  if (!(settings.mma_move > 0 && settings.mma_move <= 1))
    throw InputError("cell MMA: the move limit must be in (0, 1]");
  if (!(settings.change_tolerance >= 0)) throw InputError("cell MMA: the change tolerance must be >= 0");
  N_ = x0.rows();
  d_ = int(x0.cols());
  if (d_ != model_.parameters() || d_ > kCellMmaMaxVariables)
    throw InputError("cell MMA: " + std::to_string(d_) + " columns for a space with " +
                     std::to_string(model_.parameters()) + " parameters");
  rho_ = model_.density_index();
  // The mass is the variables' own rho column unless the filter or the
  // model's derived density put it through other cells' variables.
  mass_is_rho_ = !filtered && !model_.derives_density();

  t0_ = std::chrono::steady_clock::now();
  // The box: Poisson's ratios and moduli stay off the faces, where some
  // compliances are singular (as for Ipopt).
  xmin_.resize(d_), xmax_.resize(d_);
  for (int k = 0; k < d_; ++k) xmin_[k] = k == rho_ ? 0.0 : 1e-3, xmax_[k] = k == rho_ ? 1.0 : 1 - 1e-3;
  range_ = xmax_ - xmin_;
  x_ = x0;
  for (Eigen::Index i = 0; i < N_; ++i)
    for (int k = 0; k < d_; ++k) x_(i, k) = std::clamp(x_(i, k), xmin_[k], xmax_[k]);

  // The budget in cell volumes, less the forced-solid cells.
  V_ = objective.grid().cell_volume();
  domain_ = V_ * double(objective.grid().cells());
  double forced_mass = 0;  // as TopologyObjective::mass counts them
  for (CellRole r : objective.setup().roles) forced_mass += r == CellRole::solid ? 1.0 : 0.0;
  forced_mass *= V_;
  budget_cells_ = settings.mass_limit ? (settings.mass_budget - forced_mass) / V_ : 0.0;
  if (settings.mass_limit && budget_cells_ <= 0)
    throw InputError("cell MMA: the mass budget leaves nothing for the design cells (forced-solid cells use it all)");

  x_old1_ = x_, x_old2_ = x_, low_.resize(N_, d_), upp_.resize(N_, d_);
  cells_.resize(static_cast<std::size_t>(N_));
}

// A step can leave the space's stable region where the gamut's level set,
// padded and extrapolated, allows it (an orthotropic cell with
// nu_xy^2 >= Ex / Ey has no positive definite stiffness): the step is then
// halved towards the last iterate, as a line search would.
ObjectiveValue CellMmaRun::evaluate_with_halving(int it, MatX& g) {
  for (int halving = 0;; ++halving) {
    try {
      const ObjectiveValue v = objective_.evaluate(x_, &g);
      ++result_.evaluations;
      if (!std::isfinite(v.total)) throw NumericalError("the objective is not finite");
      return v;
    } catch (const NumericalError& e) {
      if (it == 0 || halving == kStepHalvings)
        throw NumericalError("cell MMA, iteration " + std::to_string(it) + ": " + e.what());
      spdlog::debug("cell MMA iteration {}: {}; step halved", it, e.what());
      x_ = 0.5 * (x_ + x_old1_);
    }
  }
}

void CellMmaRun::cell_conditions(MatX& cval, MatX& cjac) const {
  cval.resize(N_, m_), cjac.resize(N_ * m_, d_);
#pragma omp parallel for schedule(static)
  for (Eigen::Index i = 0; i < (m_ > 0 ? N_ : 0); ++i) {
    MatX jac;
    cval.row(i) = cell_gamut_conditions(model_, x_.row(i).transpose(), &jac).transpose();
    cjac.middleRows(i * m_, m_) = jac;
  }
}

void CellMmaRun::build_constraint(Eigen::Index i, int c, const MatX& cval, const MatX& cjac) {
  CellMmaApproximation& a = cells_[std::size_t(i)].approx;
  const CellMmaVec xi = x_.row(i).transpose(), jc = cjac.row(i * m_ + c).transpose();
  CellMmaVec pc, qc;
  a.b[c] = mma_coefficients(xi, a.lower, a.upper, jc, cval(i, c), range_, cells_[std::size_t(i)].raa[c], pc, qc);
  a.p.row(c) = pc.transpose(), a.q.row(c) = qc.transpose();
}

void CellMmaRun::build_approximations(int it, const MatX& gs, const MatX& cval, const MatX& cjac) {
  // Each cell's share of the mass: its physical rho, with d mass / d (its
  // variables).
  MatX cell_mass, cell_mass_gradient;
  if (settings_.mass_limit && !mass_is_rho_) {
    cell_mass = objective_.physical(x_).col(rho_);
    cell_mass_gradient = objective_.mass_gradient(x_) / V_;
  }
  const int d = d_, m = m_, rho = rho_;
#pragma omp parallel for schedule(static)
  for (Eigen::Index i = 0; i < N_; ++i) {
    CellMmaApproximation& a = cells_[std::size_t(i)].approx;
    a.lower.resize(d), a.upper.resize(d), a.alpha.resize(d), a.beta.resize(d);
    CellMmaVec xi(d);
    for (int k = 0; k < d; ++k) {
      const double xk = x_(i, k), r = range_[k];
      double L, U;
      if (it < 2) {
        L = xk - kAsymptoteInit * r, U = xk + kAsymptoteInit * r;
      } else {
        const double pattern = (xk - x_old1_(i, k)) * (x_old1_(i, k) - x_old2_(i, k));
        const double f = pattern > 0 ? kAsymptoteIncrease : pattern < 0 ? kAsymptoteDecrease : 1.0;
        L = xk - f * (x_old1_(i, k) - low_(i, k));
        U = xk + f * (upp_(i, k) - x_old1_(i, k));
        L = std::clamp(L, xk - kAsymptoteMax * r, xk - kAsymptoteMin * r);
        U = std::clamp(U, xk + kAsymptoteMin * r, xk + kAsymptoteMax * r);
      }
      low_(i, k) = L, upp_(i, k) = U;
      a.lower[k] = L, a.upper[k] = U;
      a.alpha[k] = std::max({xmin_[k], L + kAlbefa * (xk - L), xk - settings_.mma_move * r});
      a.beta[k] = std::min({xmax_[k], U - kAlbefa * (U - xk), xk + settings_.mma_move * r});
      xi[k] = xk;
    }
    const CellMmaVec gi = gs.row(i).transpose();
    mma_coefficients(xi, a.lower, a.upper, gi, 0.0, range_, kRaa0, a.p0, a.q0);
    a.p.resize(m, d), a.q.resize(m, d), a.b.resize(m);
    CellMmaConstraintVec& raa = cells_[std::size_t(i)].raa;
    if (raa.size() != m) raa = CellMmaConstraintVec::Constant(m, kRaa0);
    for (int c = 0; c < m; ++c) {
      raa[c] = std::max(kRaa0, kRaaDecay * raa[c]);
      build_constraint(i, c, cval, cjac);
    }
    if (settings_.mass_limit && !mass_is_rho_) {
      const CellMmaVec e = cell_mass_gradient.row(i).transpose();
      a.bm = mma_coefficients(xi, a.lower, a.upper, e, cell_mass(i, 0), range_, kRaa0, a.pm, a.qm);
    } else if (settings_.mass_limit) {
      CellMmaVec e = CellMmaVec::Zero(d);
      e[rho] = 1.0;
      a.bm = mma_coefficients(xi, a.lower, a.upper, e, xi[rho], range_, kRaa0, a.pm, a.qm);
    } else {
      a.pm = CellMmaVec::Zero(d), a.qm = CellMmaVec::Zero(d), a.bm = 0;
    }
  }
}

void CellMmaRun::solve_all(double at, double& mass, double& slope) {
  ++searches_;
#pragma omp parallel for schedule(dynamic, 256)
  for (Eigen::Index i = 0; i < N_; ++i) {
    CellState& s = cells_[std::size_t(i)];
    s.solution = solve_cell_mma(s.approx, at, s.solution.lambda, kSlackPrice, kDualTolerance);
  }
  mass = 0, slope = 0;  // summed in cell order: the same for any thread count
  for (const CellState& s : cells_) mass += s.solution.mass, slope += s.solution.mass_derivative;
}

void CellMmaRun::budget_search(double& mass, double& slope) {
  if (!settings_.mass_limit) {
    mu_ = 0;
    solve_all(0.0, mass, slope);
    return;
  }
  // From the last multiplier (the budget's price moves little from one
  // iteration to the next) unless that was the slack price; Newton steps
  // inside a bracket, decades while there is no upper end.
  double at = mu_ > 0 && mu_ < kSlackPrice ? mu_ : 0.0;
  double lo = 0, hi = std::numeric_limits<double>::infinity();
  bool capped = false;
  for (int s = 0; s < kBudgetSearches; ++s) {
    solve_all(at, mass, slope);
    const double excess = mass - budget_cells_;
    spdlog::debug("budget search {}: mu {:.10e} excess {:.3e} slope {:.3e} bracket [{:.6e}, {:.6e}]", s, at,
                  excess / budget_cells_, slope, lo, hi);
    if (excess <= kBudgetTolerance * budget_cells_ && (at == 0 || excess >= -kBudgetTolerance * budget_cells_)) break;
    if (excess > 0)
      lo = at;
    else
      hi = at;
    if (std::isfinite(hi) && hi - lo <= 1e-14 * hi) break;
    double next = slope < 0 ? at - excess / slope : std::numeric_limits<double>::quiet_NaN();
    if (!(next > lo && next < hi))
      next = !std::isfinite(hi) ? 10 * std::max(at, 1e-6) : lo > 0 ? std::sqrt(lo * hi) : 0.1 * hi;
    // Until the budget is bracketed, at most a decade per search: where the
    // mass hardly responds to mu (a parameter the objective does not see,
    // such as a family cell's rho above its member's), Newton's step from
    // the slope jumps straight to the slack price, and every cell sheds all
    // the mass its move limits allow.
    if (!std::isfinite(hi)) next = std::min(next, 10 * std::max(at, 1e-6));
    if (!std::isfinite(hi) && next >= kSlackPrice) {
      // The move limits cannot shed enough mass in one step (a start above
      // the budget): the budget gets the cells' slack price, and the excess
      // is shed over the next iterations.
      at = kSlackPrice;
      solve_all(at, mass, slope);
      capped = true;
      break;
    }
    at = next;
  }
  if (!capped && mass - budget_cells_ > kBudgetTolerance * budget_cells_ && std::isfinite(hi)) {
    at = hi;  // the feasible end of the bracket
    solve_all(at, mass, slope);
  }
  mu_ = at;
}

// Conservative? The cells whose true constraints are violated at the
// solution and above their approximations get more curvature (GCMMA's rule;
// an approximation that is low where the constraint holds to 1% of the
// constraint tolerance is left alone) and are solved again at the same mu.
int CellMmaRun::make_conservative(int it, const MatX& cval, const MatX& cjac) {
  const double violation_floor = 0.01 * settings_.constraint_tolerance;
  std::vector<char> raised(std::size_t(N_), 0), check(std::size_t(N_), 1);
  const int d = d_, m = m_;
  int rounds = 0;
  for (; m > 0 && rounds < kConservativeRounds; ++rounds) {
    std::fill(raised.begin(), raised.end(), 0);
#pragma omp parallel for schedule(dynamic, 256)
    for (Eigen::Index i = 0; i < N_; ++i) {
      if (!check[std::size_t(i)]) continue;
      CellState& st = cells_[std::size_t(i)];
      const CellMmaApproximation& a = st.approx;
      const CellMmaVec& xn = st.solution.x;
      // A cell on its slack cannot meet its constraints within the move
      // limits (a start outside the gamut); more curvature would not help.
      if (st.solution.slack > 0) continue;
      double distance = 0;
      for (int k = 0; k < d; ++k) {
        const double dx = xn[k] - x_(i, k);
        distance += (a.upper[k] - a.lower[k]) * dx * dx / ((a.upper[k] - xn[k]) * (xn[k] - a.lower[k]) * range_[k]);
      }
      if (!(distance > 0)) continue;
      const VecX values = cell_gamut_conditions(model_, VecX(xn), nullptr);
      for (int c = 0; c < m; ++c) {
        double approx = -a.b[c];
        for (int k = 0; k < d; ++k) approx += a.p(c, k) / (a.upper[k] - xn[k]) + a.q(c, k) / (xn[k] - a.lower[k]);
        if (values[c] <= violation_floor || values[c] <= approx) continue;
        st.raa[c] = 1.1 * (st.raa[c] + (values[c] - approx) / distance);
        build_constraint(i, c, cval, cjac);
        raised[std::size_t(i)] = 1;
      }
      if (raised[std::size_t(i)]) {
        st.solution = solve_cell_mma(st.approx, mu_, st.solution.lambda, kSlackPrice, kDualTolerance);
      }
    }
    long count = 0;
    for (char r : raised) count += r;
    if (count == 0) break;
    spdlog::debug("cell MMA iteration {}: round {}: {} cells not conservative", it, rounds, count);
    check = raised;
  }
  return rounds;
}

OptimizationResult CellMmaRun::run() {
  std::vector<double> objective_history;
  bool converged = false;
  std::string why;
  for (int it = 0;; ++it) {
    // 1. The objective and its gradient at the iterate.
    MatX g;
    const ObjectiveValue v = evaluate_with_halving(it, g);
    // 2. The cells' constraints and their gradients.
    MatX cval, cjac;
    cell_conditions(cval, cjac);
    double violation = m_ > 0 ? cval.maxCoeff() : -1.0;
    if (settings_.mass_limit) violation = std::max(violation, (objective_.mass(x_) - settings_.mass_budget) / domain_);
    result_.history.push_back({it, v.total, v.elastic, violation, seconds_since(t0_)});
    objective_history.push_back(v.total);
    result_.iterations = it;
    if (!converged && it >= kStallWindow && violation <= settings_.constraint_tolerance) {
      const double before = objective_history[std::size_t(it - kStallWindow)];
      if (std::abs(v.total - before) <= kStallChange * std::abs(v.total)) {
        converged = true;
        why = "converged (objective change below 1e-4 over 5 iterations)";
      }
    }
    if (converged || it == settings_.max_iterations) break;

    // 3. The smoothed gradient, scaled once so that its largest entry is 1.
    MatX gs = gradient_smoothing_.identity() ? g : gradient_smoothing_.apply(g);
    if (it == 0) {
      const double largest = gs.cwiseAbs().maxCoeff();
      if (!(std::isfinite(largest) && largest > 0))
        throw NumericalError("cell MMA: the objective's gradient at the start is zero or not finite");
      scale_ = 1.0 / largest;
    }
    gs *= scale_;

    // 4. Asymptotes and the cells' approximations.
    const auto tu = std::chrono::steady_clock::now();
    build_approximations(it, gs, cval, cjac);

    // 5. The subproblem: every cell's dual at the budget's multiplier, the
    //    budget searched again after conservative rounds.
    searches_ = 0;
    double mass = 0, slope = 0;
    budget_search(mass, slope);
    const int conservative_rounds = make_conservative(it, cval, cjac);
    if (conservative_rounds > 0 && settings_.mass_limit) {
      mass = 0;
      for (const CellState& st : cells_) mass += st.solution.mass;
      if (std::abs(mass - budget_cells_) > kBudgetTolerance * budget_cells_) budget_search(mass, slope);
    }

    // 6. The update.
    MatX x_new(N_, d_);
    double slack = 0;
    int unconverged = 0;
    for (Eigen::Index i = 0; i < N_; ++i) {
      const CellMmaSolution& s = cells_[std::size_t(i)].solution;
      x_new.row(i) = s.x.transpose();
      slack = std::max(slack, s.slack);
      unconverged += s.converged ? 0 : 1;
    }
    if (unconverged > 0) spdlog::debug("cell MMA iteration {}: {} cell duals above tolerance", it, unconverged);
    const double change = (x_new - x_).cwiseAbs().maxCoeff();
    x_old2_ = x_old1_;
    x_old1_ = x_;
    x_ = x_new;
    result_.update_seconds += seconds_since(tu);
    if (settings_.log_every > 0 && it % settings_.log_every == 0)
      spdlog::info(
          "cell-mma iteration {:4d}: S {:.6e}  elastic {:.6e}  max constraint {:.2e}  change {:.3f}  "
          "budget searches {}, conservative rounds {}  ({:.1f} s, subproblem {:.2f} s)",
          it, v.total, v.elastic, violation, change, searches_, conservative_rounds, seconds_since(t0_),
          seconds_since(tu));
    if (m_ > 0 && spdlog::should_log(spdlog::level::debug)) {
      // Which cell holds the largest violation, where, and what its
      // multipliers became: the first thing to look at when a run stalls.
      Eigen::Index wi, wc;
      cval.maxCoeff(&wi, &wc);
      std::string at, multipliers;
      for (int k = 0; k < d_; ++k) at += fmt::format(" {:.4f}", x_old1_(wi, k));
      for (int c = 0; c < m_; ++c) multipliers += fmt::format(" {:.3e}", cells_[std::size_t(wi)].solution.lambda[c]);
      spdlog::debug("cell MMA iteration {}: worst cell {} condition {} value {:.3e} at [{} ], multipliers [{} ]", it,
                    wi, wc, cval(wi, wc), at, multipliers);
    }
    if (slack > 0) spdlog::debug("cell MMA iteration {}: largest artificial slack {:.2e}", it, slack);
    if (change < settings_.change_tolerance) {
      converged = true;
      why = "converged (max change below tolerance)";
    }
  }
  result_.status = converged ? why : "iteration limit reached";
  result_.converged = converged;
  result_.q = x_;
  result_.value = objective_.evaluate(x_, nullptr);  // the cached state: no solve
  result_.max_violation = result_.history.back().max_violation;
  result_.seconds = seconds_since(t0_);
  return result_;
}

}  // namespace

OptimizationResult optimize_cell_mma(TopologyObjective& objective, const MatX& x0, const OptimizerSettings& settings,
                                     const CellFilter& gradient_smoothing) {
  return CellMmaRun(objective, x0, settings, gradient_smoothing).run();
}

}  // namespace msfab
