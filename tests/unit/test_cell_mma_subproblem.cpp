// One cell's MMA subproblem (topopt/cell_mma_subproblem.hpp): the dual's
// solution satisfies the primal's optimality conditions (KKT) checked here
// from the approximations alone, and the mass derivative used by the
// budget search matches finite differences.
#include <gtest/gtest.h>

#include <random>

#include "topopt/cell_mma_subproblem.hpp"

namespace msfab {
namespace {

// A random cell around x in the unit box: asymptotes, move limits, an
// objective gradient, `m` constraints with random values (some violated)
// and gradients, and the mass of variable d - 1.
CellMmaApproximation random_cell(std::mt19937& rng, int d, int m, CellMmaVec& x) {
  std::uniform_real_distribution<double> U(0, 1), G(-1, 1);
  CellMmaApproximation a;
  x.resize(d);
  a.lower.resize(d), a.upper.resize(d), a.alpha.resize(d), a.beta.resize(d);
  const CellMmaVec range = CellMmaVec::Ones(d);
  for (int j = 0; j < d; ++j) {
    x[j] = 0.1 + 0.8 * U(rng);
    a.lower[j] = x[j] - (0.05 + 0.5 * U(rng));
    a.upper[j] = x[j] + (0.05 + 0.5 * U(rng));
    a.alpha[j] = std::max({0.0, a.lower[j] + 0.1 * (x[j] - a.lower[j]), x[j] - 0.2});
    a.beta[j] = std::min({1.0, a.upper[j] - 0.1 * (a.upper[j] - x[j]), x[j] + 0.2});
  }
  CellMmaVec g(d);
  for (int j = 0; j < d; ++j) g[j] = G(rng);
  mma_coefficients(x, a.lower, a.upper, g, 0.0, range, 1e-5, a.p0, a.q0);
  a.p.resize(m, d), a.q.resize(m, d), a.b.resize(m);
  for (int c = 0; c < m; ++c) {
    CellMmaVec jc(d), pc, qc;
    for (int j = 0; j < d; ++j) jc[j] = G(rng);
    a.b[c] = mma_coefficients(x, a.lower, a.upper, jc, 0.3 * G(rng), range, 1e-5, pc, qc);
    a.p.row(c) = pc.transpose(), a.q.row(c) = qc.transpose();
  }
  CellMmaVec e = CellMmaVec::Zero(d);
  e[d - 1] = 1;
  a.bm = mma_coefficients(x, a.lower, a.upper, e, x[d - 1], range, 1e-5, a.pm, a.qm);
  return a;
}

double term(double p, double q, double L, double U, double x) { return p / (U - x) + q / (x - L); }
double slope(double p, double q, double L, double U, double x) {
  return p / ((U - x) * (U - x)) - q / ((x - L) * (x - L));
}

TEST(CellMmaSubproblem, DualSolutionMeetsThePrimalOptimalityConditions) {
  std::mt19937 rng(5);
  const double penalty = 1e4;
  int with_active = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const int d = 2 + trial % 4, m = trial % 6;
    CellMmaVec x0;
    const CellMmaApproximation a = random_cell(rng, d, m, x0);
    const double mu = (trial % 3 == 0) ? 0.0 : 0.5 * std::uniform_real_distribution<double>(0, 1)(rng);
    const CellMmaSolution s = solve_cell_mma(a, mu, CellMmaConstraintVec(), penalty, 1e-11);
    ASSERT_TRUE(s.converged) << "trial " << trial << " d " << d << " m " << m << " its " << s.newton_iterations
                             << " lambda " << s.lambda.transpose() << " x " << s.x.transpose() << " alpha "
                             << a.alpha.transpose() << " beta " << a.beta.transpose();
    // Primal feasibility with the artificial slack, complementarity.
    for (int c = 0; c < m; ++c) {
      double g = -a.b[c];
      for (int j = 0; j < d; ++j) g += term(a.p(c, j), a.q(c, j), a.lower[j], a.upper[j], s.x[j]);
      const double y = std::max(0.0, s.lambda[c] - penalty);
      EXPECT_GE(s.lambda[c], 0.0);
      EXPECT_LE(g - y, 1e-9) << "trial " << trial << " constraint " << c;
      EXPECT_LE(std::abs(s.lambda[c] * (g - y)), 1e-8 * std::max(1.0, s.lambda[c])) << "trial " << trial;
      with_active += s.lambda[c] > 0;
    }
    // Stationarity of the Lagrangian in x within the move limits.
    for (int j = 0; j < d; ++j) {
      double dL = slope(a.p0[j], a.q0[j], a.lower[j], a.upper[j], s.x[j]) +
                  mu * slope(a.pm[j], a.qm[j], a.lower[j], a.upper[j], s.x[j]);
      for (int c = 0; c < m; ++c) dL += s.lambda[c] * slope(a.p(c, j), a.q(c, j), a.lower[j], a.upper[j], s.x[j]);
      EXPECT_GE(s.x[j], a.alpha[j]);
      EXPECT_LE(s.x[j], a.beta[j]);
      const double tol = 1e-7 * (1 + std::abs(dL));
      if (s.x[j] > a.alpha[j] && s.x[j] < a.beta[j])
        EXPECT_NEAR(dL, 0.0, tol) << "trial " << trial << " x" << j;
      else if (s.x[j] == a.alpha[j])
        EXPECT_GE(dL, -tol) << "trial " << trial << " x" << j;
      else
        EXPECT_LE(dL, tol) << "trial " << trial << " x" << j;
    }
    // The reported mass is the approximation's value at x.
    double mass = -a.bm;
    for (int j = 0; j < d; ++j) mass += term(a.pm[j], a.qm[j], a.lower[j], a.upper[j], s.x[j]);
    EXPECT_NEAR(s.mass, mass, 1e-12 * (1 + std::abs(mass)));
  }
  EXPECT_GT(with_active, 50);  // the instances exercise active constraints
}

TEST(CellMmaSubproblem, MassDerivativeMatchesFiniteDifferences) {
  std::mt19937 rng(17);
  int checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int d = 3 + trial % 3, m = 1 + trial % 4;
    CellMmaVec x0;
    const CellMmaApproximation a = random_cell(rng, d, m, x0);
    const double mu = 0.05 + 0.5 * std::uniform_real_distribution<double>(0, 1)(rng), h = 1e-5;
    const CellMmaSolution s = solve_cell_mma(a, mu, CellMmaConstraintVec(), 1e4, 1e-12);
    const CellMmaSolution sp = solve_cell_mma(a, mu + h, s.lambda, 1e4, 1e-12);
    const CellMmaSolution sm = solve_cell_mma(a, mu - h, s.lambda, 1e4, 1e-12);
    // Finite differences hold where the active sets agree on both sides
    // and every solve met its tolerance; where the active constraints pin
    // every free variable (or one sits on its slack) the mass moves by
    // the solves' residuals alone, below what differences can resolve.
    int active = 0, free_variables = 0;
    for (int c = 0; c < m; ++c) active += s.lambda[c] > 0;
    for (int j = 0; j < d; ++j) free_variables += s.x[j] > a.alpha[j] && s.x[j] < a.beta[j];
    bool same = s.converged && sp.converged && sm.converged && s.slack == 0 && active < free_variables;
    for (int c = 0; c < m; ++c) same = same && ((sp.lambda[c] > 0) == (sm.lambda[c] > 0));
    for (int j = 0; j < d; ++j)
      same =
          same && ((sp.x[j] == a.alpha[j] || sp.x[j] == a.beta[j]) == (sm.x[j] == a.alpha[j] || sm.x[j] == a.beta[j]));
    if (!same) continue;
    const double fd = (sp.mass - sm.mass) / (2 * h);
    EXPECT_LE(s.mass_derivative, 0.0);
    EXPECT_NEAR(s.mass_derivative, fd, 1e-3 * std::abs(fd) + 1e-7) << "trial " << trial;
    ++checked;
  }
  EXPECT_GT(checked, 100);
}

TEST(CellMmaSubproblem, WarmStartGivesTheSameSolution) {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 50; ++trial) {
    CellMmaVec x0;
    const CellMmaApproximation a = random_cell(rng, 4, 4, x0);
    const CellMmaSolution cold = solve_cell_mma(a, 0.2, CellMmaConstraintVec(), 1e4, 1e-12);
    const CellMmaSolution near = solve_cell_mma(a, 0.21, cold.lambda, 1e4, 1e-12);
    const CellMmaSolution back = solve_cell_mma(a, 0.2, near.lambda, 1e4, 1e-12);
    EXPECT_LE((back.x - cold.x).cwiseAbs().maxCoeff(), 1e-9)
        << "trial " << trial << " converged " << cold.converged << near.converged << back.converged << " its "
        << cold.newton_iterations << " " << back.newton_iterations << " slack " << cold.slack << " lambda "
        << cold.lambda.transpose() << " / " << back.lambda.transpose();
    EXPECT_LE(back.newton_iterations, cold.newton_iterations + 1);
  }
}

}  // namespace
}  // namespace msfab
