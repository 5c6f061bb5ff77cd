// A density filter on a family's parameters (topopt space family3d with rho
// derived from the family, cell MMA with `filter.kind: density`): the
// derived density against the family's solid fraction and its derivative,
// the objective's and the mass's gradients through filter and derived rho
// against central differences, and cell MMA on a filtered family
// cantilever (within budget, better than its start, rho the family's).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/errors.hpp"
#include "family_test_set.hpp"
#include "gamut/material_space.hpp"
#include "gamut/microstructure_set.hpp"
#include "io/config.hpp"
#include "topopt/cell_filter.hpp"
#include "topopt/cell_mma.hpp"
#include "topopt/family_material.hpp"
#include "topopt/topology_objective.hpp"
#include "topopt/topopt_scene.hpp"

namespace msfab {
namespace {

// A cantilever 6 x 2 x 2 cells, clamped at x = 0, loaded down at the far
// bottom edge, with a filter of radius 1.5 cells.
TopoptScene filtered_family_cantilever(const std::string& extra) {
  return read_topopt_scene(Config::from_string(R"(
grid: {size: [6, 2, 2]}
space: family3d
material: {E: 1.0e6, nu: 0.3}
supports: [{box: {min: [0, 0, 0], max: [0, 2, 2]}}]
loads:
  - {objective: compliance, forces: [{box: {min: [6, 0, 0], max: [6, 2, 0]}, force: [0, 0, -1], distribute: total}]}
filter: {radius: 1.5}
)" + extra,
                                               "test"),
                           1e6, 4);
}

TEST(FamilyDensityFilter, DerivedRhoIsTheFamilysSolidFractionWithoutAConstraint) {
  const MicrostructureSet set = family_test_set();
  const auto free_rho = make_family_material_model(set, "test set");
  const auto derived = make_family_material_model(set, "test set", true);
  EXPECT_TRUE(free_rho->has_constraint());
  EXPECT_FALSE(derived->has_constraint());
  EXPECT_TRUE(derived->derives_density());
  EXPECT_FALSE(free_rho->derives_density());
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.03, 0.97);
  for (int k = 0; k < 20; ++k) {
    VecX p(3);
    p << u(rng), u(rng), u(rng);
    // Phi = rho_family - rho, so the derived rho is Phi + rho.
    EXPECT_NEAR(derived->density(p, nullptr), free_rho->constraint(p, nullptr) + p[2], 1e-14);
    EXPECT_DOUBLE_EQ(free_rho->density(p, nullptr), p[2]);
    VecX g;
    derived->density(p, &g);
    EXPECT_EQ(g[2], 0.0);
    const double h = 1e-6;
    for (int a = 0; a < 2; ++a) {
      VecX pp = p, pm = p;
      pp[a] += h, pm[a] -= h;
      EXPECT_NEAR(g[a], (derived->density(pp, nullptr) - derived->density(pm, nullptr)) / (2 * h), 1e-7);
    }
  }
  // At a member: its own solid fraction.
  VecX p(3);
  p << 0.5, 1.0, 0.0;
  EXPECT_NEAR(derived->density(p, nullptr), set.items[set.grid.item({1, 1})].properties[3], 1e-12);
}

TEST(FamilyDensityFilter, ObjectiveAndMassGradientsMatchFiniteDifferences) {
  const MicrostructureSet set = family_test_set();
  const auto model = make_family_material_model(set, "test set", true);
  TopoptScene sc = filtered_family_cantilever("mass: {target: 3, weight: 0.5}\n");
  TopologyObjective obj(sc.setup, *model);
  ASSERT_FALSE(obj.filter().identity());
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(0.2, 0.8);
  MatX q(obj.design_cells().size(), 3);
  for (Eigen::Index i = 0; i < q.size(); ++i) q(i % q.rows(), i / q.rows()) = u(rng);
  // The physical rho is the family's at the filtered parameters, whatever q's rho column holds.
  const MatX p = obj.physical(q);
  for (Eigen::Index r = 0; r < p.rows(); ++r) EXPECT_DOUBLE_EQ(p(r, 2), model->density(p.row(r).transpose(), nullptr));
  MatX g;
  const ObjectiveValue v = obj.evaluate(q, &g);
  ASSERT_GT(v.mass, 0.0);
  const MatX dm = obj.mass_gradient(q);
  double largest = 0;
  for (Eigen::Index i = 0; i < q.size(); ++i) largest = std::max(largest, std::abs(g(i % q.rows(), i / q.rows())));
  const double h = 1e-6;
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    const Eigen::Index r = i % q.rows(), k = i / q.rows();
    MatX qp = q, qm = q;
    qp(r, k) += h, qm(r, k) -= h;
    const double fd = (obj.evaluate(qp, nullptr).total - obj.evaluate(qm, nullptr).total) / (2 * h);
    EXPECT_NEAR(g(r, k), fd, 1e-5 * largest) << "cell " << r << " parameter " << k;
    EXPECT_NEAR(dm(r, k), (obj.mass(qp) - obj.mass(qm)) / (2 * h), 1e-8) << "cell " << r << " parameter " << k;
    if (k == 2) {
      EXPECT_EQ(g(r, k), 0.0);  // q's rho is not read
    }
  }
}

TEST(FamilyDensityFilter, CellMmaEndsWithinBudgetBelowItsStart) {
  const MicrostructureSet set = family_test_set();
  const auto model = make_family_material_model(set, "test set", true);
  TopoptScene sc = filtered_family_cantilever("");
  TopologyObjective obj(sc.setup, *model);
  const Eigen::Index n = Eigen::Index(obj.design_cells().size());
  MatX q0(n, 3);
  for (Eigen::Index r = 0; r < n; ++r) q0.row(r) = model->initial_point(0.4).transpose();
  OptimizerSettings os;
  os.max_iterations = 60;
  os.log_every = 0;
  os.mass_limit = true;
  os.mass_budget = 0.4 * double(n);
  const CellFilter none(obj.grid(), obj.design_cells(), 0.0);
  const OptimizationResult r = optimize_cell_mma(obj, q0, os, none);
  EXPECT_LE(obj.mass(r.q), os.mass_budget * (1 + 1e-6));
  EXPECT_GE(obj.mass(r.q), os.mass_budget * 0.98);  // compliance wants all the material it may have
  EXPECT_LT(r.value.elastic, 0.9 * r.history.front().elastic) << r.status << " after " << r.iterations;
  // Material moves to the clamped end, where the bending moment is largest.
  const MatX p = obj.physical(r.q);
  double near = 0, far = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::int64_t x = obj.design_cells()[std::size_t(i)] % 6;
    if (x < 2) near += p(i, 2);
    if (x >= 4) far += p(i, 2);
  }
  EXPECT_GT(near, far);
  // Both regularizations at once are refused.
  const CellFilter smoothing(obj.grid(), obj.design_cells(), 1.5);
  EXPECT_THROW(optimize_cell_mma(obj, q0, os, smoothing), InputError);
}

}  // namespace
}  // namespace msfab
