// Designs in a family's own parameters (topopt space family3d,
// topopt/family_material.hpp): the C^1 grid interpolant, the cell model
// built on it (stiffness, constraint and their derivatives against central
// differences; members reproduced exactly at the grid nodes) and the
// parameter grid stored with a microstructure set.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/errors.hpp"
#include "family_test_set.hpp"
#include "gamut/material_space.hpp"
#include "gamut/microstructure_set.hpp"
#include "topopt/cell_material.hpp"
#include "topopt/family_material.hpp"
#include "topopt/grid_interpolant.hpp"

namespace msfab {
namespace {

// A smooth, non-polynomial field on [0, 1]^d sampled at the grid nodes.
double family_test_field(const std::vector<double>& x, int channel) {
  double v = 0.3 * channel;
  for (std::size_t a = 0; a < x.size(); ++a) v += std::sin(1.7 * x[a] + 0.4 * double(a) + channel) * (1.0 + 0.5 * a);
  return v;
}

GridInterpolant family_test_interpolant(const std::vector<int>& sizes, int channels) {
  Eigen::Index points = 1;
  for (int n : sizes) points *= n;
  MatX values(points, channels);
  for (Eigen::Index i = 0; i < points; ++i) {
    std::vector<double> x(sizes.size());
    Eigen::Index rest = i;
    for (std::size_t a = sizes.size(); a-- > 0;) {
      const int n = sizes[a];
      x[a] = n == 1 ? 0.0 : double(rest % n) / (n - 1);
      rest /= n;
    }
    for (int c = 0; c < channels; ++c) values(i, c) = family_test_field(x, c);
  }
  return GridInterpolant(sizes, values);
}

TEST(GridInterpolant, ReproducesTheNodesAndLinearData) {
  const GridInterpolant f = family_test_interpolant({4, 3}, 2);
  VecX v;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 3; ++j) {
      VecX t(2);
      t << i / 3.0, j / 2.0;
      f.evaluate(t, v);
      for (int c = 0; c < 2; ++c) EXPECT_NEAR(v[c], family_test_field({t[0], t[1]}, c), 1e-13);
    }
  // Linear data: the Catmull-Rom tangents are the slope, so exact everywhere.
  MatX lin(5 * 2, 1);
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 2; ++j) lin(i * 2 + j, 0) = 2.0 + 3.0 * i / 4.0 - 1.5 * j;
  const GridInterpolant g({5, 2}, lin);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  for (int k = 0; k < 50; ++k) {
    VecX t(2);
    t << u(rng), u(rng);
    MatX grad;
    g.evaluate(t, v, &grad);
    EXPECT_NEAR(v[0], 2.0 + 3.0 * t[0] - 1.5 * t[1], 1e-12);
    EXPECT_NEAR(grad(0, 0), 3.0, 1e-11);
    EXPECT_NEAR(grad(0, 1), -1.5, 1e-11);
  }
}

TEST(GridInterpolant, GradientMatchesCentralDifferencesAndIsContinuous) {
  for (const std::vector<int>& sizes : {std::vector<int>{6}, std::vector<int>{2, 5}, std::vector<int>{3, 1, 4}}) {
    const GridInterpolant f = family_test_interpolant(sizes, 3);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0.02, 0.98);
    for (int k = 0; k < 40; ++k) {
      VecX t(f.axes());
      for (int a = 0; a < f.axes(); ++a) t[a] = u(rng);
      VecX v;
      MatX grad;
      f.evaluate(t, v, &grad);
      const double h = 1e-6;
      for (int a = 0; a < f.axes(); ++a) {
        VecX tp = t, tm = t, vp, vm;
        tp[a] += h, tm[a] -= h;
        f.evaluate(tp, vp), f.evaluate(tm, vm);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(grad(c, a), (vp[c] - vm[c]) / (2 * h), 1e-7) << "axis " << a;
      }
    }
    // C^1 across an interior node: one-sided slopes agree.
    const int n = sizes[0];
    if (n < 3) continue;
    VecX t = VecX::Constant(f.axes(), 0.37);
    t[0] = 1.0 / (n - 1);
    VecX left = t, right = t, v;
    MatX gl, gr;
    left[0] -= 1e-9, right[0] += 1e-9;
    f.evaluate(left, v, &gl), f.evaluate(right, v, &gr);
    EXPECT_NEAR((gl - gr).cwiseAbs().maxCoeff(), 0.0, 1e-6);
  }
}

TEST(FamilyMaterial, MembersAtTheNodesAndDerivativesMatchDifferences) {
  const MicrostructureSet set = family_test_set();
  const auto model = make_family_material_model(set, "test set");
  ASSERT_EQ(model->parameters(), 3);
  EXPECT_EQ(model->family_names(), set.grid.names);
  EXPECT_EQ(model->design_space(), "cubic3d");
  // At every node: the member's C^H, properties and half-sizes exactly.
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 2; ++j) {
      const Microstructure& m = set.items[set.grid.item({i, j})];
      VecX p(3);
      p << i / 2.0, j, m.properties[3];
      MatX C;
      model->tensor(p, C);
      EXPECT_LT((C - MatX(m.C)).norm(), 1e-9 * m.C.norm());
      VecX unit, raw;
      model->design_row(p, unit, raw);
      EXPECT_LT((raw - m.properties).cwiseQuotient(m.properties).cwiseAbs().maxCoeff(), 1e-9);
      const VecX r = model->raw(p);
      EXPECT_DOUBLE_EQ(r[0], set.grid.axes[0][std::size_t(i)]);
      EXPECT_DOUBLE_EQ(r[1], set.grid.axes[1][std::size_t(j)]);
      EXPECT_NEAR(model->constraint(p, nullptr), 0.0, 1e-12);
    }
  // Between nodes: positive definite, and dC/dp, dPhi/dp against central differences.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.03, 0.97);
  for (int k = 0; k < 30; ++k) {
    VecX p(3);
    p << u(rng), u(rng), u(rng);
    MatX C;
    std::vector<MatX> dC;
    model->tensor(p, C, &dC);
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<MatX>(C).eigenvalues().minCoeff(), 0.0);
    VecX g;
    model->constraint(p, &g);
    const double h = 1e-6;
    for (int a = 0; a < 3; ++a) {
      VecX pp = p, pm = p;
      pp[a] += h, pm[a] -= h;
      MatX Cp, Cm;
      model->tensor(pp, Cp), model->tensor(pm, Cm);
      EXPECT_LT((dC[std::size_t(a)] - (Cp - Cm) / (2 * h)).norm(), 1e-6 * C.norm()) << "parameter " << a;
      EXPECT_NEAR(g[a], (model->constraint(pp, nullptr) - model->constraint(pm, nullptr)) / (2 * h), 1e-7);
    }
    EXPECT_DOUBLE_EQ(g[2], -1.0);  // rho only pays for the member
  }
  // The start is feasible and near the requested solid fraction.
  const VecX p0 = model->initial_point(0.4);
  EXPECT_LE(model->constraint(p0, nullptr), 0.0);
  EXPECT_NEAR(p0[2], 0.4, 0.05);
}

TEST(FamilyMaterial, RefusesASetWithoutGridOrWithoutStiffness) {
  MicrostructureSet set = family_test_set();
  set.items[2].C.setZero();
  EXPECT_THROW(make_family_material_model(set, "x.h5"), InputError);
  set = family_test_set();
  set.grid = {};
  try {
    make_family_material_model(set, "x.h5");
    FAIL() << "a set without a grid was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("x.h5"), std::string::npos);
  }
  CellMaterialSettings s;
  s.space = "family3d";
  EXPECT_THROW(make_cell_material_model(s), InputError);
}

TEST(FamilyMaterial, TheSetKeepsItsGrid) {
  const MicrostructureSet set = family_test_set();
  const std::string path = ::testing::TempDir() + "msfab_family_grid.microstructures.h5";
  write_microstructures_artifact(path, set, "test", "", {}, 1);
  const MicrostructureSet back = read_microstructures_artifact(path);
  EXPECT_EQ(back.grid.names, set.grid.names);
  EXPECT_EQ(back.grid.axes, set.grid.axes);
  EXPECT_EQ(back.grid.item({2, 1}), 5u);
  MicrostructureSet bad = set;
  bad.items.pop_back();  // a stage that drops an item must clear the grid
  EXPECT_THROW(write_microstructures_artifact(path + ".bad", bad, "test", "", {}, 1), std::logic_error);
}

}  // namespace
}  // namespace msfab
