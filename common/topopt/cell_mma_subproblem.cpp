#include "topopt/cell_mma_subproblem.hpp"

#include <algorithm>
#include <cmath>

namespace msfab {
namespace {

// Armijo fraction of the projected ascent a dual step must deliver, and the
// step halvings tried before the ascent is left to round-off.
constexpr double kArmijo = 1e-4;
constexpr int kHalvings = 40;
constexpr int kMaxNewton = 100;

// The dual at (lambda, mu) and what Newton and the budget search need.
struct DualPoint {
  CellMmaVec x;
  Eigen::Matrix<bool, Eigen::Dynamic, 1, 0, kCellMmaMaxVariables, 1> free;
  double value = 0;
  CellMmaConstraintVec gradient;  // dW/dlambda_c = g~_c(x) - y_c
  CellMmaSquare hessian;          // d2W/dlambda2 (negative semi-definite)
  CellMmaConstraintVec cross;     // d2W/dlambda dmu
  // The diagonal -d2W/dlambda2 would have if every x_j were free: the
  // curvature scale of a multiplier that no free variable answers to.
  CellMmaConstraintVec clamped_curvature;
  double mass = 0;            // dW/dmu + bm: the approximate mass
  double mass_curvature = 0;  // d2W/dmu2
  double slack = 0;
};

// Plain loops over the few entries: Eigen's expressions on these tiny
// runtime-sized blocks cost more than the arithmetic (this is the inner
// loop of the optimizer: cells x budget searches x Newton steps).
DualPoint evaluate_dual(const CellMmaApproximation& a, double mu, const CellMmaConstraintVec& lambda, double penalty,
                        bool second_order) {
  const int n = a.variables(), m = a.constraints();
  DualPoint d;
  d.x.resize(n);
  d.free.resize(n);
  double P[kCellMmaMaxVariables], Q[kCellMmaMaxVariables], iu[kCellMmaMaxVariables], il[kCellMmaMaxVariables];
  double value = -mu * a.bm, mass = -a.bm;
  for (int j = 0; j < n; ++j) {
    double pj = a.p0[j] + mu * a.pm[j], qj = a.q0[j] + mu * a.qm[j];
    for (int c = 0; c < m; ++c) pj += lambda[c] * a.p(c, j), qj += lambda[c] * a.q(c, j);
    P[j] = pj, Q[j] = qj;
    const double sp = std::sqrt(pj), sq = std::sqrt(qj);
    const double xs = (a.lower[j] * sp + a.upper[j] * sq) / (sp + sq);
    d.free[j] = xs > a.alpha[j] && xs < a.beta[j];
    const double x = std::clamp(xs, a.alpha[j], a.beta[j]);
    d.x[j] = x;
    iu[j] = 1.0 / (a.upper[j] - x);
    il[j] = 1.0 / (x - a.lower[j]);
    value += pj * iu[j] + qj * il[j];
    mass += a.pm[j] * iu[j] + a.qm[j] * il[j];
  }
  d.mass = mass;
  d.gradient.resize(m);
  for (int c = 0; c < m; ++c) {
    const double y = std::max(0.0, lambda[c] - penalty);
    d.slack = std::max(d.slack, y);
    double g = -a.b[c] - y;
    for (int j = 0; j < n; ++j) g += a.p(c, j) * iu[j] + a.q(c, j) * il[j];
    d.gradient[c] = g;
    value -= lambda[c] * a.b[c] + 0.5 * y * y;
  }
  d.value = value;
  if (!second_order) return d;
  // Implicit differentiation of the free x_j: dx_j/dlambda_c = -g'_cj / phi''_j.
  double H[kCellMmaMaxConstraints][kCellMmaMaxConstraints] = {};
  double cross[kCellMmaMaxConstraints] = {};
  double gp[kCellMmaMaxConstraints];
  double mass_curvature = 0;
  double clamped[kCellMmaMaxConstraints] = {};
  for (int j = 0; j < n; ++j) {
    const double iu2 = iu[j] * iu[j], il2 = il[j] * il[j];
    const double inverse_curvature = 0.5 / (P[j] * iu2 * iu[j] + Q[j] * il2 * il[j]);
    for (int c = 0; c < m; ++c) gp[c] = a.p(c, j) * iu2 - a.q(c, j) * il2;
    if (!d.free[j]) {
      for (int c = 0; c < m; ++c) clamped[c] += gp[c] * gp[c] * inverse_curvature;
      continue;
    }
    const double mp = (a.pm[j] * iu2 - a.qm[j] * il2) * inverse_curvature;
    for (int c = 0; c < m; ++c) {
      const double gc = gp[c] * inverse_curvature;
      for (int k = 0; k <= c; ++k) H[c][k] -= gc * gp[k];
      cross[c] -= gp[c] * mp;
    }
    mass_curvature -= mp * (a.pm[j] * iu2 - a.qm[j] * il2);
  }
  d.hessian.resize(m, m);
  d.cross.resize(m);
  d.clamped_curvature.resize(m);
  for (int c = 0; c < m; ++c) {
    for (int k = 0; k <= c; ++k) d.hessian(c, k) = d.hessian(k, c) = H[c][k];
    if (lambda[c] > penalty) d.hessian(c, c) -= 1.0;
    d.cross[c] = cross[c];
    d.clamped_curvature[c] = clamped[c];
  }
  d.mass_curvature = mass_curvature;
  return d;
}

double projected_gradient(const DualPoint& d, const CellMmaConstraintVec& lambda) {
  double worst = 0;
  for (int c = 0; c < lambda.size(); ++c)
    worst = std::max(worst, lambda[c] > 0 ? std::abs(d.gradient[c]) : std::max(0.0, d.gradient[c]));
  return worst;
}

// (-H + reg) restricted to `rows`. With more constraints than free
// variables (four conditions on four parameters, one at its move limit, is
// common) -H is singular and the dual is linear along its null space up
// to the next kink; a pure Newton step runs off along it and the line
// search spends dozens of halvings cutting it back. So the diagonal is
// raised as in Marquardt's method, by 1e-3 times the projected gradient
// relative to the first one: row by row, since a multiplier on its slack
// has curvature 1 beside others of 1e-4; the shift vanishes at the
// solution (Newton's fast convergence is kept where the block is regular)
// and bounds the step elsewhere. A row no free variable answers to at all
// gets the curvature the clamped variables would give it: the length at
// which they come free.
CellMmaSquare regularized_block(const DualPoint& d, double projected,
                                const Eigen::Matrix<int, Eigen::Dynamic, 1, 0, kCellMmaMaxConstraints, 1>& rows) {
  const int k = int(rows.size());
  CellMmaSquare A(k, k);
  double scale = 0;
  for (int r = 0; r < k; ++r)
    for (int s = 0; s < k; ++s) A(r, s) = -d.hessian(rows[r], rows[s]), scale = std::max(scale, std::abs(A(r, s)));
  const double shift = std::max(1e-10, 1e-3 * std::min(1.0, projected));
  for (int r = 0; r < k; ++r) {
    const double clamped = d.clamped_curvature[rows[r]];
    A(r, r) += A(r, r) < 1e-3 * clamped ? clamped : shift * A(r, r) + 1e-14 * scale;
    if (!(A(r, r) > 0)) A(r, r) = 1e-8;  // no variable answers at all
  }
  return A;
}

}  // namespace

double mma_coefficients(const CellMmaVec& x, const CellMmaVec& lower, const CellMmaVec& upper,
                        const CellMmaVec& gradient, double value, const CellMmaVec& range, double raa0, CellMmaVec& p,
                        CellMmaVec& q) {
  const int n = int(x.size());
  p.resize(n);
  q.resize(n);
  double b = -value;
  for (int j = 0; j < n; ++j) {
    const double gpos = std::max(gradient[j], 0.0), gneg = std::max(-gradient[j], 0.0);
    const double both = 0.001 * (gpos + gneg) + raa0 / range[j];
    const double ux = upper[j] - x[j], xl = x[j] - lower[j];
    p[j] = (gpos + both) * ux * ux;
    q[j] = (gneg + both) * xl * xl;
    b += p[j] / ux + q[j] / xl;
  }
  return b;
}

CellMmaSolution solve_cell_mma(const CellMmaApproximation& a, double mu, const CellMmaConstraintVec& lambda_start,
                               double penalty, double tolerance) {
  const int m = a.constraints();
  CellMmaConstraintVec lambda =
      lambda_start.size() == m ? CellMmaConstraintVec(lambda_start.cwiseMax(0.0)) : CellMmaConstraintVec::Zero(m);
  CellMmaSolution s;
  DualPoint d = evaluate_dual(a, mu, lambda, penalty, true);
  using Rows = Eigen::Matrix<int, Eigen::Dynamic, 1, 0, kCellMmaMaxConstraints, 1>;
  const double first_gradient = std::max(projected_gradient(d, lambda), 1e-300);
  for (; s.newton_iterations < kMaxNewton && m > 0; ++s.newton_iterations) {
    if (projected_gradient(d, lambda) <= tolerance) {
      s.converged = true;
      break;
    }
    // Projected Newton (Bertsekas 1982): multipliers within eps of zero
    // whose gradient points below zero are held there; Newton acts on the
    // rest, with eps the size of a projected gradient step, so that the
    // bound set is found before the projection can spoil the direction.
    const double gradient_before = projected_gradient(d, lambda);
    double eps = 0;
    for (int c = 0; c < m; ++c) eps = std::max(eps, std::abs(lambda[c] - std::max(0.0, lambda[c] + d.gradient[c])));
    Rows rows(m);
    int k = 0;
    for (int c = 0; c < m; ++c)
      if (!(lambda[c] <= eps && d.gradient[c] < 0)) rows[k++] = c;
    rows.conservativeResize(k);
    CellMmaConstraintVec direction = CellMmaConstraintVec::Zero(m);
    if (k > 0) {
      const CellMmaSquare A = regularized_block(d, gradient_before / first_gradient, rows);
      CellMmaConstraintVec g(k);
      for (int r = 0; r < k; ++r) g[r] = d.gradient[rows[r]];
      const CellMmaConstraintVec step = A.ldlt().solve(g);
      for (int r = 0; r < k; ++r) direction[rows[r]] = step[r];
    }
    for (int c = 0; c < m; ++c)
      if (lambda[c] <= eps && d.gradient[c] < 0) direction[c] = d.gradient[c];
    // Projected backtracking along the Newton direction, then, should
    // that fail, along the gradient scaled by the largest curvature (an
    // ascent direction for small steps whenever the projected gradient is
    // not zero). W is concave; close to the solution its gain falls below
    // round-off, and a step that halves the projected gradient without
    // lowering W is taken instead.
    bool moved = false;
    double curvature = 0;
    for (int c = 0; c < m; ++c) curvature = std::max(curvature, -d.hessian(c, c));
    const CellMmaConstraintVec ascent_direction = d.gradient / (curvature > 0 ? curvature : 1.0);
    for (int attempt = 0; attempt < 2 && !moved; ++attempt) {
      const CellMmaConstraintVec& dir = attempt == 0 ? direction : ascent_direction;
      double t = 1.0;
      for (int h = 0; h < kHalvings; ++h, t *= 0.5) {
        const CellMmaConstraintVec trial = (lambda + t * dir).cwiseMax(0.0);
        const DualPoint e = evaluate_dual(a, mu, trial, penalty, false);
        const bool ascent = e.value >= d.value + kArmijo * d.gradient.dot(trial - lambda) && e.value >= d.value;
        const bool level = e.value >= d.value - 1e-13 * (1 + std::abs(d.value));
        if (ascent || (level && projected_gradient(e, trial) <= 0.5 * gradient_before)) {
          lambda = trial;
          moved = true;
          break;
        }
      }
    }
    if (!moved) break;
    d = evaluate_dual(a, mu, lambda, penalty, true);
  }
  if (m == 0) s.converged = true;
  if (!s.converged && m > 0) s.converged = projected_gradient(d, lambda) <= tolerance;
  s.x = d.x;
  s.lambda = lambda;
  s.mass = d.mass;
  s.slack = d.slack;
  // d mass / d mu along the solution: the multipliers that are positive
  // stay on their conditions (Schur complement of the dual's Hessian).
  s.mass_derivative = d.mass_curvature;
  Rows active(m);
  int k = 0;
  for (int c = 0; c < m; ++c)
    if (lambda[c] > 0) active[k++] = c;
  active.conservativeResize(k);
  if (k > 0) {
    // Without the Newton regularization: constraints that pin the same
    // free variables make the block singular, and its pseudo-inverse is
    // the limit the derivative needs.
    // Jacobi-scaled first: a multiplier on its slack adds 1 to its
    // diagonal, which can dwarf the other constraints' curvature.
    CellMmaSquare A(k, k);
    CellMmaConstraintVec h(k), w(k);
    for (int r = 0; r < k; ++r) {
      const double diagonal = -d.hessian(active[r], active[r]);
      w[r] = diagonal > 0 ? 1.0 / std::sqrt(diagonal) : 1.0;
    }
    for (int r = 0; r < k; ++r) {
      h[r] = d.cross[active[r]] * w[r];
      for (int c = 0; c < k; ++c) A(r, c) = -d.hessian(active[r], active[c]) * w[r] * w[c];
    }
    Eigen::CompleteOrthogonalDecomposition<CellMmaSquare> cod(A);
    cod.setThreshold(1e-12);
    s.mass_derivative += h.dot(cod.solve(h));
    s.mass_derivative = std::min(s.mass_derivative, 0.0);
  }
  return s;
}

}  // namespace msfab
