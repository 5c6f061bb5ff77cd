// Element and global energy / gradient / Hessian: finite differences,
// invariances, patch test, determinism.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Geometry>
#include <cstring>
#include <random>
#include <string>

#include "fem/elastic_assembler.hpp"
#include "fem/voxel_grid.hpp"
#include "material/linear_isotropic.hpp"
#include "material/neo_hookean.hpp"

using namespace msfab;

namespace {

std::vector<MaterialPtr> two_material_palette() {
  return {nullptr, std::make_shared<NeoHookean>(1e5, 0.45), std::make_shared<NeoHookean>(1e7, 0.3)};
}

VoxelGrid small_mixed_grid() {
  VoxelGrid g(3, 2, 2, 0.01, 1);
  g.at(1, 0, 0) = 2;
  g.at(2, 1, 1) = 2;
  g.at(0, 1, 0) = 0;  // a void voxel
  return g;
}

VecX perturbed(const VecX& X, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  VecX x = X;
  for (int i = 0; i < x.size(); ++i) x[i] += u(rng);
  return x;
}

// Gradient against central differences of hex_energy, Hessian against
// central differences of the gradient, and its symmetry.
void expect_element_derivatives(const hex8::ElementGeometry& geo, const QuadratureMaterials& mat,
                                const hex8::NodeMatrix& x, double hessian_tolerance, const std::string& label) {
  Vec24 g;
  Mat24 K;
  hex_evaluate(geo, mat, x, &g, &K);
  const double h = 1e-6;
  for (int k = 0; k < 24; ++k) {
    hex8::NodeMatrix xp = x, xm = x;
    xp(k / 3, k % 3) += h;
    xm(k / 3, k % 3) -= h;
    const double fd = (hex_energy(geo, mat, xp) - hex_energy(geo, mat, xm)) / (2 * h);
    EXPECT_NEAR(g[k], fd, 1e-6 * (1 + std::abs(fd))) << label << ", entry " << k;
    Vec24 gp, gm;
    hex_evaluate(geo, mat, xp, &gp, nullptr);
    hex_evaluate(geo, mat, xm, &gm, nullptr);
    const Vec24 col = (gp - gm) / (2 * h);
    EXPECT_LT((K.col(k) - col).norm(), hessian_tolerance * (1 + col.norm())) << label << ", column " << k;
  }
  EXPECT_LT((K - K.transpose()).norm(), 1e-10 * K.norm()) << label;
}

}  // namespace

TEST(Assembly, ElementGradientAndHessianMatchFiniteDifferences) {
  hex8::NodeMatrix X;
  for (int i = 0; i < 8; ++i) X.row(i) = 0.5 * (hex8::natural_node(i).transpose() + Eigen::RowVector3d::Ones());
  X(7, 0) += 0.1;  // non-cubic
  const auto geo = hex8::element_geometry(X, hex8::gauss_rule(2));
  QuadratureMaterials mat{{std::make_shared<NeoHookean>(1e3, 0.4)}};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.08, 0.08);
  hex8::NodeMatrix x = X;
  for (int i = 0; i < 8; ++i)
    for (int a = 0; a < 3; ++a) x(i, a) += u(rng);
  expect_element_derivatives(geo, mat, x, 1e-6, "trilinear");
}

TEST(EnhancedElement, GradientAndHessianOfTheCondensedEnergyMatchFiniteDifferences) {
  hex8::NodeMatrix X;
  for (int i = 0; i < 8; ++i) X.row(i) = 0.5 * (hex8::natural_node(i).transpose() + Eigen::RowVector3d::Ones());
  X(7, 0) += 0.1;  // not a parallelepiped
  for (int points : {2, 4}) {
    auto geo = hex8::enhanced_element_geometry(X, hex8::gauss_rule(points));
    if (points == 2) geo = hex8::with_centre_point(geo, X);  // the centre carries no bubble
    std::vector<MaterialPtr> per_point;
    for (int q = 0; q < geo.size(); ++q) per_point.push_back(std::make_shared<NeoHookean>(1e3 * (1 + q % 3), 0.4));
    const QuadratureMaterials mat{per_point};
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-0.08, 0.08);
    hex8::NodeMatrix x = X;
    for (int i = 0; i < 8; ++i)
      for (int a = 0; a < 3; ++a) x(i, a) += u(rng);
    const double e = hex_evaluate(geo, mat, x, nullptr, nullptr);
    EXPECT_NEAR(e, hex_energy(geo, mat, x), 1e-12 * e);
    // The bubbles lower the energy: the condensed element is softer.
    auto plain = geo;
    plain.enhanced.clear();
    EXPECT_LT(e, hex_energy(plain, mat, x));
    expect_element_derivatives(geo, mat, x, 1e-5, std::to_string(points) + " points");
  }
}

TEST(EnhancedElement, PassesThePatchTestAndBendsExactly) {
  // A 2 x 1 x 0.5 box (lengths a, b, c along x, y, z), linear material with nu = 0.
  const double a = 2.0, b = 1.0, c = 0.5, E = 1e6;
  hex8::NodeMatrix X;
  for (int i = 0; i < 8; ++i) {
    const Vec3 n = hex8::natural_node(i);
    X.row(i) << 0.5 * a * (n[0] + 1), 0.5 * b * (n[1] + 1), 0.5 * c * (n[2] + 1);
  }
  X.rowwise() += Eigen::RowVector3d(0.3, -0.2, 0.1);
  const auto enhanced = hex8::enhanced_element_geometry(X, hex8::gauss_rule(2));
  const auto plain = hex8::element_geometry(X, hex8::gauss_rule(2));
  const QuadratureMaterials linear{{std::make_shared<LinearIsotropic>(E, 0.0)}};
  // Affine deformations: the bubbles stay at rest, the energies agree.
  Mat3 G;
  G << 0.01, -0.02, 0.005, 0.003, 0.02, -0.01, 0.007, 0.011, -0.03;
  const hex8::NodeMatrix affine = X + X * G.transpose();
  EXPECT_NEAR(hex_energy(enhanced, linear, affine), hex_energy(plain, linear, affine),
              1e-10 * hex_energy(plain, linear, affine));
  // Pure bending about y: u_x = -k (x - xc)(z - zc), u_z = k (x - xc)^2 / 2 at
  // the nodes. The exact energy is E k^2 I a / 2, I = b c^3 / 12; the
  // trilinear element adds parasitic shear, the enhanced one is exact.
  const double k = 1e-3;
  const Vec3 centre = X.colwise().mean().transpose();
  hex8::NodeMatrix bent = X;
  for (int i = 0; i < 8; ++i) {
    const double dx = X(i, 0) - centre[0], dz = X(i, 2) - centre[2];
    bent(i, 0) += -k * dx * dz;
    bent(i, 2) += 0.5 * k * dx * dx;
  }
  const double exact = 0.5 * E * k * k * (b * c * c * c / 12) * a;
  EXPECT_NEAR(hex_energy(enhanced, linear, bent), exact, 1e-9 * exact);
  EXPECT_GT(hex_energy(plain, linear, bent), 2 * exact);  // locks: (a/c)^2 worth of shear
}

TEST(Assembly, GlobalGradientAndHessianMatchFiniteDifferences) {
  const VoxelMesh vm = build_voxel_mesh(small_mixed_grid(), two_material_palette());
  ElasticAssembler asmb(vm.mesh);
  const VecX x = perturbed(asmb.rest_positions(), 4e-4, 7);
  VecX g;
  SpMat K = asmb.pattern();
  asmb.evaluate(x, &g, &K);
  const double h = 1e-8;
  double max_rel_g = 0, max_rel_k = 0;
  for (int k = 0; k < x.size(); ++k) {
    VecX xp = x, xm = x;
    xp[k] += h;
    xm[k] -= h;
    const double fd = (asmb.energy(xp) - asmb.energy(xm)) / (2 * h);
    max_rel_g = std::max(max_rel_g, std::abs(g[k] - fd) / (1e-3 * g.cwiseAbs().maxCoeff() + std::abs(fd)));
    VecX gp, gm;
    asmb.evaluate(xp, &gp, nullptr);
    asmb.evaluate(xm, &gm, nullptr);
    const VecX col = (gp - gm) / (2 * h);
    max_rel_k = std::max(max_rel_k, (VecX(K.col(k)) - col).norm() / col.norm());
  }
  EXPECT_LT(max_rel_g, 1e-5);
  EXPECT_LT(max_rel_k, 1e-5);
  const SpMat Kt = K.transpose();
  EXPECT_LT((K - Kt).norm(), 1e-10 * K.norm());
}

TEST(Assembly, RigidMotionGivesZeroEnergyAndForce) {
  const VoxelMesh vm = build_voxel_mesh(small_mixed_grid(), two_material_palette());
  ElasticAssembler asmb(vm.mesh);
  const VecX X = asmb.rest_positions();
  const Mat3 R = Eigen::AngleAxisd(0.8, Vec3(1, 2, -0.5).normalized()).toRotationMatrix();
  VecX x(X.size());
  for (int i = 0; i < X.size() / 3; ++i) x.segment<3>(3 * i) = R * X.segment<3>(3 * i) + Vec3(0.1, -0.3, 2);
  VecX g;
  const double E = asmb.evaluate(x, &g, nullptr);
  EXPECT_NEAR(E, 0.0, 1e-9);
  EXPECT_LT(g.cwiseAbs().maxCoeff(), 1e-6);
  asmb.evaluate(X, &g, nullptr);
  EXPECT_NEAR(asmb.energy(X), 0.0, 1e-20);
  EXPECT_LT(g.cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Assembly, InternalForcesConserveMomentum) {
  // Sum of forces and of torques about the origin vanish for any deformation.
  const VoxelMesh vm = build_voxel_mesh(small_mixed_grid(), two_material_palette());
  ElasticAssembler asmb(vm.mesh);
  const VecX x = perturbed(asmb.rest_positions(), 2e-3, 11);
  VecX g;
  asmb.evaluate(x, &g, nullptr);
  Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
  for (int i = 0; i < x.size() / 3; ++i) {
    force += g.segment<3>(3 * i);
    torque += x.segment<3>(3 * i).cross(Vec3(g.segment<3>(3 * i)));
  }
  const double scale = g.cwiseAbs().maxCoeff();
  EXPECT_GT(scale, 1.0);
  EXPECT_LT(force.norm(), 1e-10 * scale);
  EXPECT_LT(torque.norm(), 1e-10 * scale);
}

TEST(Assembly, InvertedElementGivesInfiniteEnergyNotNaN) {
  const VoxelMesh vm = build_voxel_mesh(small_mixed_grid(), two_material_palette());
  ElasticAssembler asmb(vm.mesh);
  VecX x = asmb.rest_positions();
  // Push one node through the opposite face of its element.
  const int n = vm.mesh.elements[0][7];
  x.segment<3>(3 * n) -= Vec3(0.02, 0.02, 0.02);
  const double E = asmb.energy(x);
  EXPECT_TRUE(std::isinf(E) && E > 0);
}

// A Galerkin coarse element (ddfem/baseline_coarsening.hpp) leaves the points
// of its void voxels without material: they add no energy, and a
// deformation that inverts the element only inside a void voxel is finite.
TEST(Assembly, PointsWithoutMaterialAddNothingAndCannotInvert) {
  hex8::NodeMatrix X;
  for (int i = 0; i < 8; ++i) X.row(i) = 0.5 * (hex8::natural_node(i).transpose() + Eigen::RowVector3d::Ones());
  const auto geo = hex8::element_geometry(X, hex8::composite_gauss_rule(2, 2));
  const MaterialPtr solid = std::make_shared<NeoHookean>(1e3, 0.4);
  QuadratureMaterials full, without_corner, corner_only;
  for (int q = 0; q < geo.size(); ++q) {
    const bool in_corner_cell = q / 8 == 7;  // the sub-cube at node 7
    full.at_point.push_back(solid);
    without_corner.at_point.push_back(in_corner_cell ? nullptr : solid);
    corner_only.at_point.push_back(in_corner_cell ? solid : nullptr);
  }
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.08, 0.08);
  hex8::NodeMatrix x = X;
  for (int i = 0; i < 8; ++i)
    for (int a = 0; a < 3; ++a) x(i, a) += u(rng);
  const double e_full = hex_energy(geo, full, x);
  EXPECT_NEAR(hex_energy(geo, without_corner, x) + hex_energy(geo, corner_only, x), e_full, 1e-12 * e_full);
  expect_element_derivatives(geo, without_corner, x, 1e-6, "with void points");

  // Node 7 pushed towards the centre folds its own sub-cube only.
  hex8::NodeMatrix folded = X;
  folded.row(7) = Eigen::RowVector3d(0.5, 0.5, 0.5);
  EXPECT_TRUE(std::isinf(hex_energy(geo, full, folded)));
  EXPECT_TRUE(std::isinf(hex_energy(geo, corner_only, folded)));
  EXPECT_TRUE(std::isfinite(hex_energy(geo, without_corner, folded)));
}

TEST(Assembly, ResultsAreIndependentOfThreadCount) {
  VoxelGrid grid(6, 5, 4, 0.01, 1);
  for (size_t i = 0; i < grid.size(); i += 3) grid.ids[i] = 2;
  const VoxelMesh vm = build_voxel_mesh(grid, two_material_palette());
  ElasticAssembler asmb(vm.mesh);
  const VecX x = perturbed(asmb.rest_positions(), 5e-4, 5);
  VecX g1, g2;
  SpMat K1 = asmb.pattern(), K2 = asmb.pattern();
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const double E1 = asmb.evaluate(x, &g1, &K1);
  omp_set_num_threads(3);
  const double E2 = asmb.evaluate(x, &g2, &K2);
  omp_set_num_threads(saved);
  EXPECT_EQ(E1, E2);
  EXPECT_EQ((g1 - g2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(std::memcmp(K1.valuePtr(), K2.valuePtr(), sizeof(double) * K1.nonZeros()), 0);
}

TEST(VoxelMesh, OnlySolidVoxelsBecomeElementsWithSharedNodes) {
  VoxelGrid g(2, 1, 1, 1.0, 1);
  auto vm = build_voxel_mesh(g, two_material_palette());
  EXPECT_EQ(vm.mesh.num_elements(), 2);
  EXPECT_EQ(vm.mesh.num_nodes(), 12);  // two cubes sharing a face
  g.at(1, 0, 0) = 0;
  vm = build_voxel_mesh(g, two_material_palette());
  EXPECT_EQ(vm.mesh.num_elements(), 1);
  EXPECT_EQ(vm.mesh.num_nodes(), 8);
  g.at(0, 0, 0) = 0;
  EXPECT_ANY_THROW(build_voxel_mesh(g, two_material_palette()));
  g.at(0, 0, 0) = 5;  // not in the palette
  EXPECT_ANY_THROW(build_voxel_mesh(g, two_material_palette()));
}

namespace {

// A non-parallelepiped element with a different material at each of its
// 4 x 4 x 4 points (as a level-2 DDFEM element) and a random deformation.
struct EnhancedCase {
  hex8::NodeMatrix X, x;
  hex8::ElementGeometry geo;
  QuadratureMaterials mat;
};
EnhancedCase enhanced_case(double amplitude) {
  EnhancedCase c;
  for (int i = 0; i < 8; ++i) c.X.row(i) = 0.5 * (hex8::natural_node(i).transpose() + Eigen::RowVector3d::Ones());
  c.X(7, 0) += 0.1;
  c.geo = hex8::enhanced_element_geometry(c.X, hex8::gauss_rule(4));
  for (int q = 0; q < c.geo.size(); ++q)
    c.mat.at_point.push_back(std::make_shared<NeoHookean>(1e3 * (1 + q % 5), 0.45));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  c.x = c.X;
  for (int i = 0; i < 8; ++i)
    for (int a = 0; a < 3; ++a) c.x(i, a) += u(rng);
  return c;
}

}  // namespace

TEST(EnhancedElement, KeptStateGivesTheColdResultsAndPredictsTheBubblesToSecondOrder) {
  const EnhancedCase c = enhanced_case(0.06);
  Vec24 g_cold, g;
  Mat24 K_cold, K;
  const double e_cold = hex_evaluate(c.geo, c.mat, c.x, &g_cold, &K_cold);
  // A state that has been elsewhere (a gradient at other positions, then
  // an energy at third ones) gives the cold results at x.
  BubbleState state;
  hex8::NodeMatrix elsewhere = c.x;
  elsewhere.col(2) *= 1.02;
  Vec24 g_elsewhere;
  hex_evaluate(c.geo, c.mat, elsewhere, &g_elsewhere, nullptr, &state);
  elsewhere.col(0) *= 0.99;
  hex_evaluate(c.geo, c.mat, elsewhere, nullptr, nullptr, &state);
  const double e = hex_evaluate(c.geo, c.mat, c.x, &g, &K, &state);
  EXPECT_NEAR(e, e_cold, 1e-13 * e_cold);
  EXPECT_LT((g - g_cold).norm(), 1e-10 * g_cold.norm());
  EXPECT_LT((K - K_cold).norm(), 1e-10 * K_cold.norm());
  ASSERT_TRUE(state.has_model);

  // Along a direction, the prediction's error falls with the square of the
  // distance (the held amplitudes' with the distance itself).
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  hex8::NodeMatrix d;
  for (int i = 0; i < 8; ++i)
    for (int a = 0; a < 3; ++a) d(i, a) = u(rng);
  double previous_error = 0;
  for (double s : {1e-2, 1e-3}) {
    const hex8::NodeMatrix xs = c.x + s * d;
    Mat3 exact;
    ASSERT_TRUE(hex_condensed_bubbles(c.geo, c.mat, xs, exact));
    const double predicted_error = (state.predicted(xs) - exact).norm();
    const double held_error = (state.model_A - exact).norm();
    EXPECT_LT(predicted_error, 0.05 * held_error) << "step " << s;
    if (previous_error > 0) {
      EXPECT_LT(predicted_error, 0.03 * previous_error);
    }
    previous_error = predicted_error;
  }
  // An energy evaluation nearby starts from the prediction and needs at
  // most two Newton steps; it equals the cold one.
  const hex8::NodeMatrix near = c.x + 1e-3 * d;
  BubbleState kept = state;
  const double e_near = hex_evaluate(c.geo, c.mat, near, nullptr, nullptr, &kept);
  EXPECT_NEAR(e_near, hex_energy(c.geo, c.mat, near), 1e-13 * e_near);
  EXPECT_LE(kept.evaluations, 3);
  // At the positions it last condensed at, the state is reused as it is.
  Vec24 g_near, g_near_cold;
  hex_evaluate(c.geo, c.mat, near, &g_near, nullptr, &kept);
  EXPECT_EQ(kept.evaluations, 0);
  hex_evaluate(c.geo, c.mat, near, &g_near_cold, nullptr);
  EXPECT_LT((g_near - g_near_cold).norm(), 1e-10 * g_near_cold.norm());
}

TEST(EnhancedElement, CondensationAtSmallStrainsEndsInsteadOfBacktrackingInRoundOff) {
  // At strains of 1e-6 to 1e-10 the bubbles' last Newton steps change F by
  // less than its round-off, so the energies a line search compares are
  // equal or noise; it halved such steps 40 times per iteration (360-380
  // evaluations for one condensation before the round-off rule).
  for (double amplitude : {1e-6, 1e-8, 1e-10}) {
    const EnhancedCase c = enhanced_case(amplitude);
    BubbleState state;
    EXPECT_TRUE(std::isfinite(hex_evaluate(c.geo, c.mat, c.x, nullptr, nullptr, &state)));
    EXPECT_LE(state.evaluations, 4) << "cold, strain " << amplitude;
    hex8::NodeMatrix moved = c.x;
    moved(3, 1) += 1e-3 * amplitude;
    hex_evaluate(c.geo, c.mat, moved, nullptr, nullptr, &state);
    EXPECT_LE(state.evaluations, 4) << "warm, strain " << amplitude;
    // The amplitudes are the linear problem's: a deformation twice as large
    // gives twice the amplitudes.
    const hex8::NodeMatrix doubled = c.X + 2 * (c.x - c.X);
    Mat3 A1, A2;
    ASSERT_TRUE(hex_condensed_bubbles(c.geo, c.mat, c.x, A1));
    ASSERT_TRUE(hex_condensed_bubbles(c.geo, c.mat, doubled, A2));
    EXPECT_GT(A1.norm(), 0);
    EXPECT_LT((A2 - 2 * A1).norm(), 1e-4 * A2.norm()) << "strain " << amplitude;
  }
}
