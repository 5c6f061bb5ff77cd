// The full-resolution check (thesis Table 3.1, common/verify): coarse
// entities and their weights, supports carried to the fine grid (a clamped
// face stays a face, an edge an edge, prescribed values interpolated), point
// supports moved off void, loads spread with their totals kept and never on
// void, the sampling of the fine displacement at the coarse nodes, and a
// solid bar pulled by a prescribed displacement, where both models agree.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/errors.hpp"
#include "topopt/cell_material.hpp"
#include "topopt/grid_elasticity.hpp"
#include "verify/comparison.hpp"
#include "verify/refinement.hpp"

namespace msfab {
namespace {

// A linear field u(x) = A x + b, per unknown of a grid.
VecX linear_field(const CellGrid& g, const Mat3& A, const Vec3& b) {
  VecX u(g.unknowns());
  for (std::int64_t n = 0; n < g.nodes(); ++n) u.segment<3>(n * 3) = A * g.node_position(n) + b;
  return u;
}

std::vector<char> coarse_face_fixed(const CellGrid& g, int axis, int index, const std::vector<int>& comps) {
  std::vector<char> fixed(std::size_t(g.unknowns()), 0);
  for (std::int64_t n = 0; n < g.nodes(); ++n)
    if (g.node_coords(n)[std::size_t(axis)] == index)
      for (int a : comps) fixed[std::size_t(n * 3 + a)] = 1;
  return fixed;
}

TEST(VerifyRefinement, EntitiesInterpolateLinearFieldsExactly) {
  const CellGrid coarse(3, 3, 2, 2, 0.5);
  const CellRefinement ref(coarse, 4);
  EXPECT_EQ(ref.fine().nx(), 12);
  EXPECT_DOUBLE_EQ(ref.fine().h(), 0.125);
  Mat3 A;
  A << 0.3, -1.2, 0.5, 2.0, 0.1, -0.7, 0.4, 0.9, 1.1;
  const Vec3 b(0.2, -0.4, 0.6);
  const VecX uc = linear_field(coarse, A, b);
  for (std::int64_t x = 0; x < ref.fine().nodes(); ++x) {
    const CellRefinement::Entity e = ref.entity(x);
    const auto f = ref.fine().node_coords(x);
    int spanned = 0;
    for (int a = 0; a < 3; ++a) spanned += f[std::size_t(a)] % 4 != 0;
    ASSERT_EQ(e.corners, 1 << spanned);
    double sum = 0;
    Vec3 u = Vec3::Zero();
    for (int c = 0; c < e.corners; ++c) {
      sum += e.weight[c];
      u += e.weight[c] * uc.segment<3>(e.node[c] * 3);
    }
    EXPECT_NEAR(sum, 1.0, 1e-14);
    EXPECT_LT((u - (A * ref.fine().node_position(x) + b)).norm(), 1e-12);
  }
  EXPECT_EQ(ref.fine_node_of(coarse.node_index(3, 2, 1)), ref.fine().node_index(12, 8, 4));
  EXPECT_THROW(CellRefinement(CellGrid(2, 4, 4, 1, 1.0), 4), InputError);
}

TEST(VerifyRefinement, ClampedFaceStaysAFaceAndValuesInterpolate) {
  const CellGrid coarse(3, 4, 2, 2, 1.0);
  const CellRefinement ref(coarse, 4);
  const CellGrid& fine = ref.fine();
  const std::vector<char> material(std::size_t(fine.nodes()), 1);
  const CellRefinement::Supports s = ref.refine_supports(coarse_face_fixed(coarse, 0, 0, {0, 1, 2}), material);
  for (std::int64_t x = 0; x < fine.nodes(); ++x)
    for (int a = 0; a < 3; ++a) EXPECT_EQ(s.fixed[std::size_t(x * 3 + a)], fine.node_coords(x)[0] == 0 ? 1 : 0);
  EXPECT_EQ(s.point_supports, 0);
  // Prescribed values: a linear field on the face is reproduced.
  Mat3 A = Mat3::Zero();
  A(0, 1) = 0.01, A(2, 2) = -0.02, A(1, 2) = 0.03;
  const VecX uf = s.values * linear_field(coarse, A, Vec3(0.001, 0, 0));
  const VecX exact = linear_field(fine, A, Vec3(0.001, 0, 0));
  for (std::int64_t d = 0; d < fine.unknowns(); ++d)
    if (s.fixed[std::size_t(d)]) {
      EXPECT_NEAR(uf[d], exact[d], 1e-15);
    }

  // An edge (x = 0, z = 0) fixed in z only: the fine nodes of that edge.
  std::vector<char> edge(std::size_t(coarse.unknowns()), 0);
  for (int j = 0; j <= 2; ++j) edge[std::size_t(coarse.node_index(0, j, 0) * 3 + 2)] = 1;
  const CellRefinement::Supports se = ref.refine_supports(edge, material);
  for (std::int64_t x = 0; x < fine.nodes(); ++x) {
    const auto f = fine.node_coords(x);
    EXPECT_EQ(se.fixed[std::size_t(x * 3 + 2)], f[0] == 0 && f[2] == 0 ? 1 : 0);
    EXPECT_EQ(se.fixed[std::size_t(x * 3)], 0);
  }
}

TEST(VerifyRefinement, PointSupportOnVoidMovesToNearestMaterial) {
  const CellGrid coarse(3, 2, 2, 2, 1.0);
  const CellRefinement ref(coarse, 4);
  const CellGrid& fine = ref.fine();
  std::vector<char> fixed(std::size_t(coarse.unknowns()), 0);
  const std::int64_t corner = coarse.node_index(0, 0, 0);
  fixed[std::size_t(corner * 3 + 1)] = 1;
  std::vector<char> material(std::size_t(fine.nodes()), 1);
  material[std::size_t(fine.node_index(0, 0, 0))] = 0;  // the corner itself is void
  const CellRefinement::Supports s = ref.refine_supports(fixed, material);
  EXPECT_EQ(s.point_supports, 1);
  EXPECT_EQ(s.moved_point_supports, 1);
  int held = 0;
  for (std::int64_t x = 0; x < fine.nodes(); ++x) {
    if (!s.fixed[std::size_t(x * 3 + 1)]) continue;
    const auto f = fine.node_coords(x);
    EXPECT_LE(std::max({f[0], f[1], f[2]}), 1);
    // On an outer face through the corner, one fine node away (or the corner itself).
    EXPECT_TRUE(f[0] == 0 || f[1] == 0 || f[2] == 0);
    ++held;
  }
  // The corner and its ring at distance 1 on the three faces: (1, 1, 1) is inside.
  EXPECT_EQ(held, 1 + 6);
  const std::vector<std::int64_t> near = ref.nearest_material(corner, material, 2);
  EXPECT_EQ(near.size(), 6u);
}

TEST(VerifyRefinement, FaceLoadKeepsItsTotalAndStaysOnTheFace) {
  const CellGrid coarse(3, 4, 2, 2, 1.0);
  const CellRefinement ref(coarse, 4);
  const CellGrid& fine = ref.fine();
  VecX f = VecX::Zero(coarse.unknowns());
  int loaded = 0;
  for (std::int64_t n = 0; n < coarse.nodes(); ++n)
    if (coarse.node_coords(n)[0] == 4) ++loaded;
  for (std::int64_t n = 0; n < coarse.nodes(); ++n)
    if (coarse.node_coords(n)[0] == 4) f.segment<3>(n * 3) = Vec3(0.1, 0, -1.0) / loaded;
  std::vector<char> material(std::size_t(fine.nodes()), 1);
  CellRefinement::LoadStats st;
  VecX ff = ref.refine_forces(f, material, "test", &st);
  EXPECT_EQ(st.loaded_nodes, 9);
  EXPECT_EQ(st.point_loads, 0);
  EXPECT_EQ(st.fine_nodes, 9 * 9);
  Vec3 total = Vec3::Zero(), moment = Vec3::Zero(), coarse_moment = Vec3::Zero();
  for (std::int64_t x = 0; x < fine.nodes(); ++x) {
    const Vec3 fx = ff.segment<3>(x * 3);
    if (fx.squaredNorm() > 0) {
      EXPECT_EQ(fine.node_coords(x)[0], 16);
    }
    total += fx;
    moment += fine.node_position(x).cross(fx);
  }
  for (std::int64_t n = 0; n < coarse.nodes(); ++n) coarse_moment += coarse.node_position(n).cross(f.segment<3>(n * 3));
  EXPECT_LT((total - Vec3(0.1, 0, -1.0)).norm(), 1e-14);
  EXPECT_LT((moment - coarse_moment).norm(), 1e-13);  // a symmetric load keeps its moment

  // Void nodes on the face take nothing; the total is kept.
  std::mt19937 rng(5);
  for (std::int64_t x = 0; x < fine.nodes(); ++x)
    if (rng() % 3 == 0) material[std::size_t(x)] = 0;
  ff = ref.refine_forces(f, material, "test", &st);
  total.setZero();
  for (std::int64_t x = 0; x < fine.nodes(); ++x) {
    if (!material[std::size_t(x)]) {
      EXPECT_EQ(ff.segment<3>(x * 3).squaredNorm(), 0.0);
    }
    total += ff.segment<3>(x * 3);
  }
  EXPECT_LT((total - Vec3(0.1, 0, -1.0)).norm(), 1e-14);
}

// The consistent coarse load of a uniform traction (corners 1/4, edges 1/2
// of an interior node's share) becomes the consistent fine load of the same
// traction.
TEST(VerifyRefinement, UniformTractionStaysUniform) {
  const CellGrid coarse(3, 4, 2, 2, 0.5);
  const CellRefinement ref(coarse, 4);
  const CellGrid& fine = ref.fine();
  const Vec3 t(0.3, -1.0, 0.2);  // traction on the face x = max
  auto lumped = [](const CellGrid& g, std::int64_t n) {
    const auto c = g.node_coords(n);
    double a = g.h() * g.h();
    if (c[1] == 0 || c[1] == g.ny()) a *= 0.5;
    if (c[2] == 0 || c[2] == g.nz()) a *= 0.5;
    return a;
  };
  VecX f = VecX::Zero(coarse.unknowns());
  for (std::int64_t n = 0; n < coarse.nodes(); ++n)
    if (coarse.node_coords(n)[0] == coarse.nx()) f.segment<3>(n * 3) = lumped(coarse, n) * t;
  const VecX ff = ref.refine_forces(f, std::vector<char>(std::size_t(fine.nodes()), 1), "test");
  for (std::int64_t x = 0; x < fine.nodes(); ++x) {
    const Vec3 expected = fine.node_coords(x)[0] == fine.nx() ? Vec3(lumped(fine, x) * t) : Vec3::Zero();
    EXPECT_LT((ff.segment<3>(x * 3) - expected).norm(), 1e-15) << "fine node " << x;
  }
}

TEST(VerifyRefinement, PointLoadSpreadsOverTheSurfacePatch) {
  const CellGrid coarse(3, 4, 2, 2, 1.0);
  const CellRefinement ref(coarse, 4);
  const CellGrid& fine = ref.fine();
  VecX f = VecX::Zero(coarse.unknowns());
  const std::int64_t tip = coarse.node_index(4, 1, 2);  // on the faces x = max and z = max
  f.segment<3>(tip * 3) = Vec3(0, 0, -2);
  const std::vector<char> material(std::size_t(fine.nodes()), 1);
  CellRefinement::LoadStats st;
  const VecX ff = ref.refine_forces(f, material, "test", &st);
  EXPECT_EQ(st.point_loads, 1);
  Vec3 total = Vec3::Zero(), moment = Vec3::Zero();
  for (std::int64_t x = 0; x < fine.nodes(); ++x) {
    const Vec3 fx = ff.segment<3>(x * 3);
    if (fx.squaredNorm() == 0) continue;
    const auto p = fine.node_coords(x);
    EXPECT_TRUE(p[0] == 16 || p[2] == 8);
    EXPECT_LE(std::abs(p[0] - 16), 3);
    EXPECT_LE(std::abs(p[1] - 4), 3);
    EXPECT_LE(std::abs(p[2] - 8), 3);
    total += fx;
    moment += fine.node_position(x).cross(fx);
  }
  EXPECT_LT((total - Vec3(0, 0, -2)).norm(), 1e-14);
  // Symmetric in y about the node.
  EXPECT_NEAR(moment[0] / -2.0, 1.0, 1e-12);

  // Nothing with material within a cell: an input error naming the case.
  const std::vector<char> none(std::size_t(fine.nodes()), 0);
  try {
    ref.refine_forces(f, none, "load case 'tip'");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("load case 'tip': the force at grid node [4, 1, 2]"), std::string::npos);
  }
}

TEST(VerifyComparison, InterpolatedFieldMatchesAndVoidIsSampledNearby) {
  const CellGrid coarse(3, 2, 2, 2, 1.0);
  const CellRefinement ref(coarse, 4);
  Mat3 A;
  A << 0.01, 0.02, 0, -0.01, 0.03, 0.01, 0.02, 0, -0.02;
  const Vec3 b(0.001, 0.002, -0.003);
  const VecX uc = linear_field(coarse, A, b), uf = linear_field(ref.fine(), A, b);
  std::vector<char> material(std::size_t(ref.fine().nodes()), 1);
  const std::vector<char> active(std::size_t(coarse.nodes()), 1);
  DisplacementComparison c = compare_displacements(ref, uc, uf, material, active);
  EXPECT_EQ(c.compared, coarse.nodes());
  EXPECT_EQ(c.nearest, 0);
  EXPECT_LT(c.relative, 1e-12);
  // The centre node void: the mean of its 26 neighbours is the linear field's value.
  material[std::size_t(ref.fine().node_index(4, 4, 4))] = 0;
  c = compare_displacements(ref, uc, uf, material, active);
  EXPECT_EQ(c.nearest, 1);
  EXPECT_EQ(c.kind[std::size_t(coarse.node_index(1, 1, 1))], SampleKind::nearest);
  EXPECT_LT(c.relative, 1e-12);
  // A field twice as large: 100%.
  c = compare_displacements(ref, uc, 2 * uf, material, active);
  EXPECT_NEAR(c.relative, 1.0, 1e-12);
  EXPECT_NEAR(relative_difference(2.0, 2.2), 0.1, 1e-12);
}

// A solid bar on rollers, its end pulled by a prescribed displacement: the
// coarse and fine models carry the same uniform strain exactly.
TEST(VerifyComparison, SolidBarPulledAgreesOnBothGrids) {
  const CellGrid coarse(3, 4, 2, 2, 1.0);
  const CellRefinement ref(coarse, 4);
  const CellGrid& fine = ref.fine();
  std::vector<char> fixed(std::size_t(coarse.unknowns()), 0);
  VecX prescribed = VecX::Zero(coarse.unknowns());
  for (std::int64_t n = 0; n < coarse.nodes(); ++n) {
    const auto c = coarse.node_coords(n);
    if (c[0] == 0 || c[0] == 4) fixed[std::size_t(n * 3)] = 1;
    if (c[0] == 4) prescribed[n * 3] = 0.01;
    if (c[0] == 0 && c[1] == 1) fixed[std::size_t(n * 3 + 1)] = 1;
    if (c[0] == 0 && c[2] == 1) fixed[std::size_t(n * 3 + 2)] = 1;
  }
  const std::vector<char> material(std::size_t(fine.nodes()), 1);
  const CellRefinement::Supports s = ref.refine_supports(fixed, material);
  const MatX C = isotropic_voigt(3, 1e6, 0.3);
  auto pairs_of = [&](const CellGrid& g) {
    MatX p(g.cells(), 21);
    for (int a = 0; a < 6; ++a)
      for (int t = a; t < 6; ++t) p.col(CellGrid::pair_index(a, t, 6)).setConstant(C(a, t));
    return p;
  };
  GridElasticity hom(coarse, fixed, "cholmod", {});
  hom.set_stiffness(pairs_of(coarse));
  GridElasticity full(fine, s.fixed, "cholmod", {});
  full.set_stiffness(pairs_of(fine));
  const VecX uc = hom.solve(VecX::Zero(coarse.unknowns()), prescribed);
  const VecX uf = full.solve(VecX::Zero(fine.unknowns()), s.values * prescribed);
  const DisplacementComparison c =
      compare_displacements(ref, uc, uf, material, std::vector<char>(std::size_t(coarse.nodes()), 1));
  EXPECT_LT(c.relative, 1e-9);
  EXPECT_LT(relative_difference(hom.energy(uc), full.energy(uf)), 1e-9);
  EXPECT_NEAR(hom.energy(uc), 0.5 * 1e6 * (0.01 / 4) * (0.01 / 4) * 16, 1e-6);
}

}  // namespace
}  // namespace msfab
