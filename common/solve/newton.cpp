#include "solve/newton.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <unsupported/Eigen/IterativeSolvers>

#include "core/errors.hpp"
#include "core/timing.hpp"
#include "solve/cholmod_solver.hpp"
#include "solve/load_continuation.hpp"
#include "solve/multigrid_solver.hpp"
#include "solve/regularized_step.hpp"

namespace msfab {
namespace {

using Clock = std::chrono::steady_clock;

// Relative round-off of the total potential, as a fraction of force scale x
// length scale (the size of the first-order terms that cancel in it):
// ~10^6 x machine epsilon, generous so that element counts and aspect
// ratios that grow those terms stay covered. Below it, energy differences
// are noise and the line search measures the decrease by the directional
// derivative instead.
constexpr double kEnergyRoundOff = 1e-10;
// A prescribed DOF within this fraction of the body's size of its target
// is there (prescribed_gap).
constexpr double kClosedGap = 1e-12;

// The diagonal of the body's rest bounding box: the length prescribed gaps
// and round-off floors are measured against.
double body_size(const ElasticAssembler& assembler) {
  return (assembler.mesh().bbox_max() - assembler.mesh().bbox_min()).norm();
}

double mean_free_diagonal(const SpMat& K, const std::vector<char>& fixed) {
  double sum = 0;
  int count = 0;
  for (int c = 0; c < K.outerSize(); ++c) {
    if (fixed[c]) continue;
    sum += std::abs(K.coeff(c, c));
    ++count;
  }
  return count ? sum / count : 1.0;
}

}  // namespace

void constrain_matrix(SpMat& K, const std::vector<char>& fixed, double diag) {
  for (int c = 0; c < K.outerSize(); ++c) {
    for (SpMat::InnerIterator it(K, c); it; ++it) {
      const int r = static_cast<int>(it.row());
      if (fixed[c] || fixed[r]) it.valueRef() = (r == c) ? diag : 0.0;
    }
  }
}

int DirichletConditions::count_fixed() const {
  int n = 0;
  for (char f : fixed) n += f ? 1 : 0;
  return n;
}

std::string format_history(const std::vector<NewtonIteration>& history, size_t max_lines) {
  return format_iteration_table(history, max_lines,
                                "  step  load    iter  residual     energy         alpha      shift\n",
                                [](const NewtonIteration& h) { return newton_iteration_columns(h) + "\n"; });
}

std::string static_linear_solver(double dofs, const NewtonOptions& options) {
  if (options.linear_solver != "auto") return options.linear_solver;
  return dofs < options.auto_iterative_dofs ? "cholmod" : "pcg-mg";
}

double static_solve_peak_bytes(double elements, double dofs, const NewtonOptions& options) {
  const double assembled = 10e3 * elements;
  return static_linear_solver(dofs, options) == "cholmod" ? assembled + 1e3 * std::pow(elements, 4.0 / 3.0) : assembled;
}

namespace {

// The linear solver options solve_static uses: the multigrid hierarchy on the
// mesh's unknown nodes unless the caller gave a lattice.
LinearSolverOptions static_linear_options(const ElasticAssembler& assembler, const std::string& solver_name,
                                          const NewtonOptions& options) {
  LinearSolverOptions linear = options.linear;
  if (solver_name == "pcg-mg" && !linear.node_positions)
    linear.node_positions =
        std::make_shared<const NodeArray>(assembler.unknown_rest_nodes());  // the MG hierarchy's lattice
  return linear;
}

// The Newton step with the prescribed DOFs eliminated, K_ff dx_f = -g_f -
// K_fc gap_c and dx_c = gap_c, regularized (solve_regularized_step) until it
// descends where no prescribed DOF is still to be moved. K is the tangent
// after constrain_matrix with `diag`; Kgap is the tangent times gap before
// that (not read where gap_norm is 0). One rule for solve_static's
// iterations and newton_step_from.
// Its right-hand side for the tangent shifted by `shift`: -g_f - K_fc gap_c
// on the free DOFs, (diag + shift) gap_c on the fixed ones.
void constrained_newton_rhs(const std::vector<char>& fixed, const VecX& g, const VecX& gap, double gap_norm,
                            const VecX& Kgap, double diag, double shift, VecX& b) {
  for (Eigen::Index i = 0; i < g.size(); ++i)
    b[i] = fixed[std::size_t(i)] ? (diag + shift) * gap[i] : -g[i] - (gap_norm > 0 ? Kgap[i] : 0.0);
}

RegularizedStep constrained_newton_step(LinearSolver& solver, const SpMat& K, double diag,
                                        const std::vector<char>& fixed, const VecX& g, const VecX& gap, double gap_norm,
                                        const VecX& Kgap, VecX& rhs, VecX& dx, const char* context) {
  const int n = static_cast<int>(g.size());
  return solve_regularized_step(
      solver, K, diag,
      [&](double shift, VecX& b) { constrained_newton_rhs(fixed, g, gap, gap_norm, Kgap, diag, shift, b); },
      [&](VecX& candidate) {
        double slope = 0;
        for (int i = 0; i < n; ++i)
          if (!fixed[i]) slope += g[i] * candidate[i];
        return gap_norm > 0 || slope < 0;
      },
      rhs, dx, context);
}

// The prescribed DOFs' remaining move, target - x on the fixed DOFs. A gap
// below 1e-12 of the body's size is the round-off of x + dx after a full
// step (dx_c = gap_c by construction) and is closed: set to zero, so that
// it neither switches off the descent test and the line search (both only
// apply once every prescribed DOF is where it must be) nor enters the
// right-hand side. Before, a gap of 1e-19 let a step that raised the
// twisting bar's energy from 2.3e-3 to 7.0e2 through, and Newton took 92
// iterations instead of 35.
double prescribed_gap(const std::vector<char>& fixed, const VecX& target, const VecX& x, double length_scale,
                      VecX& gap) {
  gap.setZero(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i)
    if (fixed[std::size_t(i)]) gap[i] = target[i] - x[i];
  const double norm = gap.norm();
  if (norm > kClosedGap * length_scale) return norm;
  gap.setZero();
  return 0;
}

// The first shift of the preconditioners of indefinite_direct_solve and
// indefinite_multigrid_solve, relative to the mean diagonal. A
// preconditioner needs no smaller one, and the regularization schedule's
// 1e-8 spent eight failed factorizations before reaching it (bridge_arch:
// 1.5 s against 0.7 s; 1e-3 and up double the MINRES iterations).
constexpr double kFirstPreconditionerShift = 1e-4;

// The preconditioner interface Eigen's MINRES calls, for any z = M^-1 r.
template <class Apply>
struct AppliedPreconditioner {
  Apply apply;
  VecX solve(const VecX& v) const { return apply(v); }
};

// MINRES on K x = b from x = 0 (to 1e-10, at most `max_iterations`) with
// the preconditioner `apply`: x where it reached a relative residual of
// 1e-8, else empty. `what` names the preconditioner in the debug log.
template <class Apply>
VecX preconditioned_minres(const SpMat& K, const VecX& b, Apply apply, Eigen::Index max_iterations,
                           const std::string& what, Clock::time_point t0) {
  VecX x = VecX::Zero(b.size());
  Eigen::Index iterations = max_iterations;
  double tolerance = 1e-10;
  Eigen::internal::minres(K, b, x, AppliedPreconditioner<Apply>{std::move(apply)}, iterations, tolerance);
  const double residual = (K * x - b).norm() / b.norm();
  spdlog::debug("newton_step_from: MINRES on the indefinite tangent, {}, {} iterations, residual {:.1e}, {:.3f} s",
                what, iterations, residual, seconds_since(t0));
  if (x.allFinite() && residual <= 1e-8) return x;
  return VecX();
}

// Solves K x = b for a symmetric K that is not positive definite: MINRES
// preconditioned by the L L^T factor of K + s I, s the first of a growing
// sequence of shifts that makes it positive definite. Its operator's
// eigenvalues are l / (l + s), near 1 except for the few eigenvalues l of K
// at or below s, so MINRES needs a few iterations: 0.7 s in all on
// bridge_arch's 24 k unknowns, where simplicial L D L^T took 1.7 s. That
// is the fallback where MINRES stalls. Empty where both fail.
VecX indefinite_direct_solve(const SpMat& K, const VecX& b, double scale, const LinearSolverOptions& linear) {
  if (b.norm() == 0) return VecX::Zero(b.size());
  const auto t0 = Clock::now();
  CholmodSolver shifted(linear);
  shifted.analyze(K);
  const RegularizationSchedule schedule;
  double shift = kFirstPreconditionerShift * scale;
  bool factored = false;
  for (int attempt = 0; attempt < schedule.max_factorizations && !factored; ++attempt, shift *= schedule.growth)
    factored = shifted.factorize(K, shift);
  if (factored) {
    // 17-25 iterations on the ten scenes' tangents; where the shift had to
    // reach far into the spectrum MINRES stalls, and L D L^T is cheaper
    // than more of it (random3: 200 iterations, 1.2 s, residual 2e-4).
    VecX x = preconditioned_minres(
        K, b, [&shifted](const VecX& v) { return shifted.solve(v); }, 60,
        fmt::format("factor of shift {:.2e} (analysis {:.3f} s, last factorization {:.3f} s)", shift / schedule.growth,
                    shifted.stats().analyze_seconds, shifted.stats().factorize_seconds),
        t0);
    if (x.size() > 0) return x;
  }
  LinearSolverOptions ldlt_options = linear;
  ldlt_options.indefinite = true;
  CholmodSolver ldlt(ldlt_options);
  ldlt.analyze(K);
  if (!ldlt.factorize(K)) return VecX();
  VecX x = ldlt.solve(b);
  spdlog::debug("newton_step_from: L D L^T, {} negative pivots, relative residual {:.1e}, {:.3f} s",
                ldlt.negative_pivots(), ldlt.stats().relative_residual, seconds_since(t0));
  // Without pivoting, L D L^T can lose accuracy on an indefinite matrix.
  if (!x.allFinite() || ldlt.stats().relative_residual > 1e-8) return VecX();
  return x;
}

// On a voxel lattice: MINRES on K x = b preconditioned by the multigrid
// cycle of K + s I. MINRES needs a positive definite preconditioner, which
// the cycle is once K + s I is; the multigrid's own checks (definite
// diagonal blocks and coarsest level) do not prove that, so a shift whose
// MINRES does not reach the residual is taken as too small, and the next
// one tried, up to `max_stalled` such shifts (a caller with a direct
// fallback gives up early: each costs up to 200 cycles). Empty where none
// does.
VecX indefinite_multigrid_solve(const SpMat& K, const VecX& b, double scale, const LinearSolverOptions& linear,
                                int max_stalled) {
  if (b.norm() == 0) return VecX::Zero(b.size());
  const auto t0 = Clock::now();
  MultigridSolver shifted(linear);
  shifted.analyze(K);
  const RegularizationSchedule schedule;
  double shift = kFirstPreconditionerShift * scale;
  int stalled = 0;
  for (int attempt = 0; attempt < schedule.max_factorizations && stalled < max_stalled;
       ++attempt, shift *= schedule.growth) {
    if (!shifted.factorize(K, shift)) continue;
    VecX x = preconditioned_minres(
        K, b, [&shifted](const VecX& v) { return shifted.apply_preconditioner(v); }, 200,
        fmt::format("multigrid of shift {:.2e}", shift), t0);
    if (x.size() > 0) return x;
    ++stalled;
  }
  return VecX();
}

}  // namespace

NewtonStepFrom newton_step_from(const ElasticAssembler& assembler, const DirichletConditions& dirichlet,
                                const VecX& force, const NewtonOptions& options, const VecX& x) {
  const int n = assembler.num_dofs();
  if (x.size() != n || force.size() != n || static_cast<int>(dirichlet.fixed.size()) != n)
    throw std::invalid_argument("newton_step_from: DOF vectors do not match the mesh");
  SpMat K = assembler.pattern();
  VecX g(n);
  if (!std::isfinite(assembler.evaluate(x, &g, &K))) return {VecX(), "an element is inverted (det F <= 0)"};
  g -= force;
  const VecX target = assembler.rest_positions() + dirichlet.displacement;
  VecX gap;
  const double gap_norm = prescribed_gap(dirichlet.fixed, target, x, body_size(assembler), gap);
  const VecX Kgap = K * gap;
  const double diag = mean_free_diagonal(K, dirichlet.fixed);
  constrain_matrix(K, dirichlet.fixed, diag);
  VecX step(n), rhs(n);
  constrained_newton_rhs(dirichlet.fixed, g, gap, gap_norm, Kgap, diag, 0.0, rhs);
  // An estimate needs the step itself, not a descent direction. First the
  // solver solve_static would use, which takes a positive definite tangent.
  const std::string solver_name = static_linear_solver(n, options);
  const auto t0 = Clock::now();
  const auto solver = make_linear_solver(solver_name, static_linear_options(assembler, solver_name, options));
  solver->analyze(K);
  if (solver->factorize(K)) {
    try {
      step = solver->solve(rhs);
      spdlog::debug("newton_step_from: {} solve {:.3f} s", solver_name, seconds_since(t0));
      if (step.allFinite()) return {std::move(step), ""};
    } catch (const NumericalError&) {  // PCG met negative curvature
    }
  }
  spdlog::debug("newton_step_from: {} found the tangent indefinite in {:.3f} s", solver_name, seconds_since(t0));
  // Not positive definite: the exact step. On a voxel lattice first MINRES
  // preconditioned by the multigrid (the ten adaptive scenes' fine
  // tangents: 0.09 s against 0.35 s for the shifted factorization on
  // bridge_arch's 24 k unknowns, the same step); where it stalls, or the
  // static solver is CHOLMOD, the direct solve where a factorization fits.
  const bool direct_fits = n <= options.largest_indefinite_direct_step;
  if (solver_name == "pcg-mg") {
    step = indefinite_multigrid_solve(K, rhs, diag, static_linear_options(assembler, solver_name, options),
                                      direct_fits ? 2 : std::numeric_limits<int>::max());
    if (step.size() > 0) {
      // Their rows are diag x_i = diag gap_i: exact, not to MINRES's tolerance.
      for (int i = 0; i < n; ++i)
        if (dirichlet.fixed[i]) step[i] = gap[i];
      return {std::move(step), "", 0.0, true};
    }
  }
  if (direct_fits) {
    step = indefinite_direct_solve(K, rhs, diag, static_linear_options(assembler, "cholmod", options));
    if (step.size() == 0)
      return {VecX(), fmt::format("the indefinite tangent could not be solved ({}MINRES on the shifted factor "
                                  "stalled, L D L^T met a zero pivot or lost accuracy)",
                                  solver_name == "pcg-mg" ? "MINRES on the multigrid stalled, " : "")};
    return {std::move(step), "", 0.0, true};
  }
  // Otherwise regularized as the solver's own Newton steps are.
  const RegularizedStep regularized = constrained_newton_step(*solver, K, diag, dirichlet.fixed, g, gap, gap_norm, Kgap,
                                                              rhs, step, "newton_step_from: ");
  if (!regularized.ok) return {VecX(), "the tangent could not be solved even with regularization", 0.0};
  return {std::move(step), "", regularized.shift};
}

namespace {

// Newton's method on one static problem (thesis Algorithm 1): the solver,
// work vectors and the iteration at one load factor.
class StaticNewton {
 public:
  StaticNewton(const ElasticAssembler& assembler, const DirichletConditions& dirichlet, const VecX& force,
               const NewtonOptions& options, NewtonResult& result)
      : assembler_(assembler),
        dirichlet_(dirichlet),
        fixed_(dirichlet.fixed),
        force_(force),
        options_(options),
        result_(result),
        n_(assembler.num_dofs()),
        X_(assembler.rest_positions()),
        length_scale_(body_size(assembler)),
        K_(assembler.pattern()),
        g_(n_),
        gap_(n_),
        rhs_(n_),
        dx_(n_),
        Kgap_(n_),
        g_trial_(n_),
        trial_(n_) {
    const std::string solver_name = static_linear_solver(n_, options);
    solver_ = make_linear_solver(solver_name, static_linear_options(assembler, solver_name, options));
    spdlog::debug("linear solver: {}", solver_->name());
    const auto t0 = Clock::now();
    solver_->analyze(K_);
    result_.timings.solve += seconds_since(t0);
  }

  // Runs Newton at load factor s from result.x; true on convergence, else
  // `why` says what failed.
  bool at(double s, int step, std::string& why);

 private:
  struct LineSearch {
    bool accepted = false;
    double alpha = 1;
    bool round_off_step = false;  // a full step where energy differences are noise
  };
  LineSearch line_search(const VecX& fs, double potential, double gap_norm, double scale);

  double free_norm(const VecX& v) const {
    double s = 0;
    for (int i = 0; i < n_; ++i)
      if (!fixed_[i]) s += v[i] * v[i];
    return std::sqrt(s);
  }
  double fixed_norm(const VecX& v) const {
    double s = 0;
    for (int i = 0; i < n_; ++i)
      if (fixed_[i]) s += v[i] * v[i];
    return std::sqrt(s);
  }
  // Every iteration's record goes to the history and to the caller's hook.
  void add_record(const NewtonIteration& rec) {
    result_.history.push_back(rec);
    if (options_.on_iteration) options_.on_iteration(rec);
  }

  const ElasticAssembler& assembler_;
  const DirichletConditions& dirichlet_;
  const std::vector<char>& fixed_;
  const VecX& force_;
  const NewtonOptions& options_;
  NewtonResult& result_;
  const int n_;
  const VecX X_;
  const double length_scale_;
  SpMat K_;
  std::unique_ptr<LinearSolver> solver_;
  VecX g_, gap_, rhs_, dx_, Kgap_, g_trial_, trial_;
};

// Backtracking line search on the total potential (Armijo) into trial_; an
// inverted state has +inf energy and is always rejected. While the
// prescribed gap is still open the potential may rise, so only feasibility
// is required.
//
// Near equilibrium the decrease asked for falls below the round-off of the
// potential itself: the elastic energy is a sum of first-order terms
// (I1 - 3 against ln J) that cancel to second order, so its absolute error
// is ~eps x force x length while the decrease is ~residual^2. Armijo on the
// energy alone then rejects every step (a Neo-Hookean cantilever under a
// tiny tip load stalled for 54 iterations). When the change of the
// potential is within that round-off, the decrease is measured by the
// directional derivative, which has no such cancellation: the trapezoid
// estimate alpha/2 (g.dx + g_trial.dx), exact for a quadratic potential,
// must meet the same Armijo condition.
StaticNewton::LineSearch StaticNewton::line_search(const VecX& fs, double potential, double gap_norm, double scale) {
  double slope = 0;
  for (int i = 0; i < n_; ++i)
    if (!fixed_[i]) slope += g_[i] * dx_[i];
  const double energy_round_off = kEnergyRoundOff * scale * length_scale_;
  LineSearch out;
  for (int ls = 0; ls < options_.max_line_search; ++ls, out.alpha *= 0.5) {
    trial_ = result_.x + out.alpha * dx_;
    const double Et = assembler_.energy(trial_);
    if (!std::isfinite(Et)) continue;
    const double pt = Et - fs.dot(trial_ - X_);
    const bool within_round_off = std::abs(pt - potential) <= energy_round_off;
    out.accepted = gap_norm > 0 || pt <= potential + options_.armijo * out.alpha * slope;
    if (!out.accepted && within_round_off) {
      assembler_.evaluate(trial_, &g_trial_, nullptr);
      double slope_trial = 0;
      for (int i = 0; i < n_; ++i)
        if (!fixed_[i]) slope_trial += (g_trial_[i] - fs[i]) * dx_[i];
      out.accepted = 0.5 * (slope + slope_trial) <= options_.armijo * slope;
    }
    out.round_off_step = out.accepted && out.alpha == 1.0 && within_round_off && gap_norm == 0;
    if (out.accepted) break;
  }
  return out;
}

bool StaticNewton::at(double s, int step, std::string& why) {
  const VecX fs = s * force_;
  VecX target = X_ + s * dirichlet_.displacement;
  double stiffness_scale = 0;
  // Round-off floor: consecutive full steps taken where energy differences
  // are noise (see the line search) that no longer halve the residual.
  double previous_residual = 0;
  bool round_off_step = false;
  int stagnant_steps = 0;
  for (int it = 0; it <= options_.max_iterations; ++it) {
    auto t0 = Clock::now();
    const double E = assembler_.evaluate(result_.x, &g_, &K_);
    if (!std::isfinite(E)) {
      why = "the configuration is inverted (an element has det F <= 0)";
      return false;
    }
    g_ -= fs;
    const double potential = E - fs.dot(result_.x - X_);
    const double gap_norm = prescribed_gap(fixed_, target, result_.x, length_scale_, gap_);
    if (gap_norm > 0) Kgap_ = K_ * gap_;
    const double diag = mean_free_diagonal(K_, fixed_);
    if (stiffness_scale == 0) stiffness_scale = diag;
    // Force scale: applied loads and the reactions at prescribed DOFs.
    const double scale = std::max({fs.norm(), fixed_norm(g_), 1e-12 * stiffness_scale * length_scale_});
    const double residual = free_norm(g_) / scale;
    result_.timings.assembly += seconds_since(t0);

    NewtonIteration rec;
    rec.load_step = step;
    rec.load_factor = s;
    rec.iteration = it;
    rec.residual = residual;
    rec.energy = potential;
    const bool gap_closed = gap_norm == 0;
    stagnant_steps = (round_off_step && residual > 0.5 * previous_residual) ? stagnant_steps + 1 : 0;
    previous_residual = residual;
    if (gap_closed && residual <= options_.relative_tolerance) {
      add_record(rec);
      return true;
    }
    // The gradient has a round-off floor too (positions are the unknowns,
    // so strains come from F - I): a tolerance below it cannot be met.
    // Two full Newton steps in the round-off regime of the energy that do
    // not halve the residual mean the floor is reached; that is the
    // solution, and more iterations only redraw the noise.
    if (gap_closed && stagnant_steps >= 2) {
      add_record(rec);
      spdlog::warn(
          "Newton: the residual stagnates at {:.2e}, the round-off level of this problem, above the "
          "tolerance {:.1e}; accepted as converged",
          residual, options_.relative_tolerance);
      return true;
    }
    if (it == options_.max_iterations) {
      add_record(rec);
      why = "no convergence in " + std::to_string(options_.max_iterations) + " iterations";
      return false;
    }

    // Newton step with inertia regularization: if the Hessian is not
    // positive definite (or the step is not a descent direction) a growing
    // multiple of the identity is added, as interior-point codes do.
    t0 = Clock::now();
    constrain_matrix(K_, fixed_, diag);
    const RegularizedStep regularized =
        constrained_newton_step(*solver_, K_, diag, fixed_, g_, gap_, gap_norm, Kgap_, rhs_, dx_, "");
    const double shift = regularized.shift;
    result_.timings.solve += seconds_since(t0);
    spdlog::debug("linear solver {}: factorize {:.3f} s, solve {:.3f} s, {} iterations", solver_->name(),
                  solver_->stats().factorize_seconds, solver_->stats().solve_seconds, solver_->stats().iterations);
    rec.shift = shift;
    rec.linear_iterations = solver_->stats().iterations;
    if (!regularized.ok) {
      add_record(rec);
      why = "the Newton system could not be solved even with regularization";
      // A shift does not help an iterative solver that ran out of
      // iterations: say what it reported (e.g. the key of its limit).
      if (!regularized.last_linear_error.empty())
        why += "; the linear solver reported: " + regularized.last_linear_error;
      return false;
    }

    t0 = Clock::now();
    const LineSearch searched = line_search(fs, potential, gap_norm, scale);
    round_off_step = searched.round_off_step;
    const bool accepted = searched.accepted;
    const double alpha = searched.alpha;
    result_.timings.line_search += seconds_since(t0);
    rec.step_length = accepted ? alpha : 0;
    add_record(rec);
    spdlog::debug("newton load {:.4f} iter {:2d} residual {:.3e} energy {:.6e} alpha {:.3g} shift {:.2e}", s, it,
                  residual, potential, rec.step_length, shift);
    if (!accepted) {
      why = "line search failed to find a decrease";
      return false;
    }
    result_.x = trial_;
    ++result_.iterations;
  }
  return false;
}

}  // namespace

NewtonResult solve_static(const ElasticAssembler& assembler, const DirichletConditions& dirichlet, const VecX& force,
                          const NewtonOptions& options, const VecX& x0) {
  const auto t_start = Clock::now();
  const int n = assembler.num_dofs();
  if (static_cast<int>(dirichlet.fixed.size()) != n || dirichlet.displacement.size() != n || force.size() != n)
    throw std::invalid_argument("solve_static: DOF vectors do not match the mesh");

  NewtonResult result;
  result.x = x0.size() == n ? x0 : assembler.rest_positions();
  StaticNewton newton(assembler, dirichlet, force, options, result);

  // Load stepping with adaptive halving of failing increments.
  VecX x_saved;
  LoadContinuation continuation;
  continuation.steps = options.load_steps;
  continuation.max_halvings = options.max_step_halvings;
  continuation.solve_at = [&](double s, int step, std::string& why) { return newton.at(s, step, why); };
  continuation.save = [&] { x_saved = result.x; };
  continuation.restore = [&] { result.x = x_saved; };
  continuation.on_converged = [&](double s) {
    spdlog::debug("load factor {:.4f} converged ({} Newton iterations so far)", s, result.iterations);
    if (options.on_load_step) options.on_load_step(s);
  };
  continuation.on_halving = [](double s, const std::string& why) {
    spdlog::warn("load factor {:.4f} failed ({}); halving the load increment", s, why);
  };
  const LoadContinuationResult loaded = continue_load(continuation);
  if (!loaded.converged) {
    std::ostringstream msg;
    msg << "Newton failed at load factor " << loaded.failed_at << " after " << options.max_step_halvings
        << " load-step halvings: " << loaded.why;
    result.failure = msg.str();
  }
  result.converged = loaded.converged;
  result.load_steps = loaded.load_steps;
  result.timings.total = seconds_since(t_start);
  return result;
}

}  // namespace msfab
