// DDFEM coarse-material fitting: fine blocks, force-space sampling,
// anisotropy directions, NNLS and the regularized fit (thesis §2.3.1-2.3.3).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "core/errors.hpp"
#include "ddfem/anisotropy.hpp"
#include "ddfem/coarse_fit.hpp"
#include "ddfem/fine_block.hpp"
#include "ddfem/force_samples.hpp"
#include "ddfem/level2_block.hpp"
#include "ddfem/nnls.hpp"
#include "ddfem_test_blocks.hpp"
#include "fem/elastic_assembler.hpp"
#include "material/neo_hookean.hpp"

namespace msfab {
namespace {

using ddfem_test::kVoxel;
using ddfem_test::layered_ids;
using ddfem_test::two_materials;

void print_fit(const char* label, const CoarseMaterialFit& f) {
  std::printf("[ddfem] %-28s train %.4f heldout %.4f (energy %.4f) samples %d/%d dropped %d inverted %d  %.2f s\n",
              label, f.residual, f.heldout_error, f.heldout_energy_error, f.samples_train, f.samples_heldout,
              f.samples_dropped, f.samples_coarse_inverted, f.seconds);
}

TEST(DdfemFineBlock, CornersAndChildOrder) {
  const auto pal = two_materials(1e6, 1e8);
  const FineBlock block = make_fine_block(layered_ids(), pal, kVoxel);
  EXPECT_EQ(block.mesh().num_elements(), 8);
  EXPECT_EQ(block.mesh().num_nodes(), 27);
  ASSERT_TRUE(block.has_all_corners());
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  for (int c = 0; c < 8; ++c) {
    const Vec3 p = block.mesh().nodes.row(block.corner_nodes[c]).transpose();
    EXPECT_NEAR((p - X.row(c).transpose()).norm(), 0.0, 1e-15);
    EXPECT_EQ(block.child_material[c], pal[(c & 1) ? 2 : 1]);
  }
  // Coarse Gauss point k lies in child child_of_coarse_point(k).
  const auto rule = hex8::gauss_rule(2);
  for (int q = 0; q < 8; ++q) {
    const int c = FineBlock::child_of_coarse_point(q);
    const Vec3 pos = kVoxel * (rule.points[q] + Vec3::Ones());
    EXPECT_EQ(int(pos.x() > kVoxel), c >> 2 & 1);
    EXPECT_EQ(int(pos.y() > kVoxel), c >> 1 & 1);
    EXPECT_EQ(int(pos.z() > kVoxel), c & 1);
  }
  BlockMaterials with_void = layered_ids();
  with_void[5] = 0;
  const FineBlock holed = make_fine_block(with_void, pal, kVoxel);
  EXPECT_FALSE(holed.has_all_corners());
  EXPECT_EQ(holed.corner_nodes[5], -1);
  const CoarseMaterialFit f = fit_coarse_material(holed, ddfem_test::small_fit_options());
  EXPECT_FALSE(f.fitted);
  EXPECT_FALSE(f.not_fitted_reason.empty());
  EXPECT_THROW(make_fine_block(BlockMaterials{}, pal, kVoxel), InputError);
  EXPECT_THROW(make_fine_block(BlockMaterials{1, 1, 1, 1, 1, 1, 1, 3}, pal, kVoxel), InputError);
}

TEST(DdfemSampling, RigidMotionConstraintsCarryNoReaction) {
  const FineBlock block = make_fine_block(layered_ids(), two_materials(1e6, 1e8), kVoxel);
  const BlockSolver solver(block);
  // The null space is orthonormal and annihilated by the constraints.
  const MatX& Z = solver.null_space();
  EXPECT_EQ(Z.cols(), block.mesh().num_dofs() - 6);
  EXPECT_LT((Z.transpose() * Z - MatX::Identity(Z.cols(), Z.cols())).norm(), 1e-12);
  EXPECT_LT((solver.constraint_matrix() * Z).norm(), 1e-12 * kVoxel * Z.rows());
  ForceSamplingOptions o;
  o.sphere_directions = 1;
  const auto patterns = make_force_patterns(block, o);
  // 4 directions x 4 kinds + 12 edges.
  EXPECT_EQ(patterns.size(), 4u * 4u + 12u);
  const int n = block.mesh().num_nodes();
  for (const ForcePattern& p : patterns) {
    Vec3 net = Vec3::Zero(), moment = Vec3::Zero();
    for (int i = 0; i < n; ++i) {
      net += p.force.segment<3>(3 * i);
      moment += block.mesh().nodes.row(i).transpose().cross(Vec3(p.force.segment<3>(3 * i)));
    }
    EXPECT_LT(net.norm(), 1e-12);
    EXPECT_LT(moment.norm(), 1e-12 * kVoxel);
  }
  // Self-equilibrated dead loads have no net moment about the REST
  // positions; about the deformed ones they do, by O(strain) x load, and the
  // constraints carry it. So: reactions vanish in the linear limit and stay
  // O(strain) relative to the load at finite strain. All kinds, both signs
  // (compression included) converge to the branch that starts at rest.
  const MatX& G = solver.constraint_matrix();
  for (int which : {0, 1, 4 + 2, 4 * 3 + 3, 20}) {  // stretch, shear, bend, twist, pinch
    const ForcePattern& p = patterns[which];
    for (double strain : {1e-5, 0.1, -0.1}) {
      const double load = strain / solver.linear_peak_strain(p.force);
      const VecX f = load * p.force;
      VecX start;
      BlockSolver::Solution s;
      for (int step = 1; step <= 5; ++step) {  // the continuation sample_force_space uses
        s = solver.solve(step / 5.0 * f, start);
        ASSERT_TRUE(s.converged) << force_kind_name(p.kind) << " strain " << strain << " step " << step;
        start = s.x;
      }
      VecX g;
      solver.assembler().evaluate(s.x, &g, nullptr);
      const VecX reaction = g - f;
      const double fnorm = f.norm();
      // (At 1e-5 strain the solver stops at its round-off floor.)
      EXPECT_LT((Z.transpose() * reaction).norm(), (std::abs(strain) < 1e-3 ? 1e-6 : 1e-8) * fnorm)
          << force_kind_name(p.kind);
      // Net reaction force, and moment in units of force (divided by h).
      VecX net = G * reaction;
      net.tail<3>() /= kVoxel;
      EXPECT_LT(net.norm(), 10 * std::abs(strain) * fnorm) << force_kind_name(p.kind) << " strain " << strain;
      EXPECT_GT(s.energy, 0.0);
      // Equal and opposite small loads: nearly equal energies (no rotated
      // or flipped branch, whose energy would be unrelated).
      if (std::abs(strain) < 1e-3) {
        const auto opposite = solver.solve(-f);
        ASSERT_TRUE(opposite.converged);
        EXPECT_NEAR(opposite.energy / s.energy, 1.0, 1e-3);
      }
    }
  }
}

TEST(DdfemNnls, MatchesKnownAndBruteForceSolutions) {
  // A = I: the solution clips negative entries of b.
  const NnlsResult id = solve_nnls(MatX::Identity(3, 3), Vec3(1.0, -2.0, 3.0));
  ASSERT_TRUE(id.converged);
  EXPECT_NEAR((id.x - Vec3(1.0, 0.0, 3.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(id.residual, 2.0, 1e-12);

  // Random problems against enumeration of all passive sets.
  std::mt19937_64 rng(5);
  auto u = [&] { return double(rng() >> 11) * 0x1.0p-53 * 2.0 - 1.0; };
  int with_active = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const int m = 9, n = 5;
    MatX A(m, n);
    VecX b(m);
    for (int i = 0; i < m; ++i) {
      b[i] = u();
      for (int j = 0; j < n; ++j) A(i, j) = u();
    }
    double best = 1e300;
    VecX best_x;
    for (int mask = 0; mask < (1 << n); ++mask) {
      std::vector<int> cols;
      for (int j = 0; j < n; ++j)
        if (mask >> j & 1) cols.push_back(j);
      VecX x = VecX::Zero(n);
      if (!cols.empty()) {
        MatX Ap(m, cols.size());
        for (size_t k = 0; k < cols.size(); ++k) Ap.col(k) = A.col(cols[k]);
        const VecX z = Ap.colPivHouseholderQr().solve(b);
        if (z.minCoeff() < 0) continue;
        for (size_t k = 0; k < cols.size(); ++k) x[cols[k]] = z[k];
      }
      const double r = (A * x - b).norm();
      if (r < best) best = r, best_x = x;
    }
    const NnlsResult s = solve_nnls(A, b);
    ASSERT_TRUE(s.converged);
    EXPECT_GE(s.x.minCoeff(), 0.0);
    EXPECT_NEAR(s.residual, best, 1e-10);
    EXPECT_NEAR((s.x - best_x).norm(), 0.0, 1e-8);
    if ((best_x.array() == 0.0).any()) ++with_active;
  }
  EXPECT_GT(with_active, 5);  // the constraints were active in many trials
}

TEST(DdfemFit, HomogeneousBlockRecoversItsMaterial) {
  const auto pal = two_materials(1e6, 1e8);
  const FineBlock block = make_fine_block(BlockMaterials{1, 1, 1, 1, 1, 1, 1, 1}, pal, kVoxel);
  CoarseFitOptions o = ddfem_test::small_fit_options();
  const ForceSampleSet samples = sample_force_space(block, o.sampling);
  EXPECT_EQ(samples.dropped, 0);
  const std::vector<Vec3> dirs(8, Vec3::UnitX());
  const double mu = pal[1]->shear_modulus(), lambda = pal[1]->lame_lambda();

  // Stretching, shearing and twisting move a homogeneous block's corners
  // like a trilinear element with the fine material would: the fit must
  // return that material and predict held-out energies almost exactly.
  o.kind_weight = {1.0, 1.0, 0.0, 1.0, 0.0};
  const CoarseMaterialFit exact = fit_from_samples(block, samples, dirs, o);
  print_fit("homogeneous, smooth kinds", exact);
  ASSERT_TRUE(exact.fitted);
  EXPECT_GT(exact.samples_heldout, 10);
  EXPECT_LT(exact.heldout_error, 0.01);
  for (int k = 0; k < 8; ++k) {
    EXPECT_NEAR(exact.mu[k] / mu, 1.0, 0.02) << k;
    EXPECT_NEAR(exact.lambda[k] / lambda, 1.0, 0.05) << k;
  }

  // Bending and pinching store energy the 24-DOF element cannot mirror
  // (it locks in bending; a pinch is local): with every kind the fit trades
  // these off, softening the element, and the held-out error says how much.
  o.kind_weight = CoarseFitOptions().kind_weight;
  const CoarseMaterialFit all = fit_from_samples(block, samples, dirs, o);
  print_fit("homogeneous, all kinds", all);
  ASSERT_TRUE(all.fitted);
  EXPECT_GT(all.heldout_error, exact.heldout_error);
  EXPECT_LT(all.heldout_error, 0.4);
  for (int k = 0; k < 8; ++k) {
    EXPECT_GT(all.mu[k], 0.3 * mu) << k;
    EXPECT_LT(all.mu[k], 1.05 * mu) << k;
  }
}

// A stiff fiber along x: children (i, 0, 0), soft elsewhere.
BlockMaterials fiber_ids() {
  BlockMaterials ids;
  for (int c = 0; c < 8; ++c) ids[c] = (c & 3) == 0 ? 2 : 1;
  return ids;
}

TEST(DdfemFit, FiberBlockDirectionIsTheFiberAndSpringsNeverHurt) {
  const FineBlock block = make_fine_block(fiber_ids(), two_materials(1e6, 1e8), kVoxel);
  CoarseFitOptions o = ddfem_test::small_fit_options();
  const ForceSampleSet samples = sample_force_space(block, o.sampling);
  std::printf("[ddfem] fiber sampling: %zu samples, %d dropped, %.3f s (%.0f samples/s)\n", samples.samples.size(),
              samples.dropped, samples.seconds, samples.attempted / samples.seconds);
  EXPECT_LE(samples.dropped, 2);
  // The stiffest direction, found from stretch samples alone, is the fiber.
  const AnisotropyEstimate dirs = estimate_anisotropy(block, o.anisotropy);
  for (int k = 0; k < 8; ++k) EXPECT_GT(std::abs(dirs.direction[k].x()), 0.9) << k;

  // The isotropic model is the anisotropic one with C = 0 (C's regularizer
  // target), so the minimized objective can only drop.
  const CoarseMaterialFit with = fit_from_samples(block, samples, dirs.direction, o);
  o.anisotropic = false;
  const CoarseMaterialFit without = fit_from_samples(block, samples, dirs.direction, o);
  print_fit("fiber 100x anisotropic", with);
  print_fit("fiber 100x isotropic", without);
  ASSERT_TRUE(with.fitted && without.fitted);
  EXPECT_LE(with.objective, without.objective * (1 + 1e-10));
}

// Eq. 2.8 as written (fit.residual: absolute, balance_kinds: false, unit
// kind weights, no regularizer) minimizes the plain sum of squared energy
// errors; the default minimizes the sum of squared relative errors. Each
// fit must be at least as good as the other in its own measure, and on a
// fibre block, whose samples span two decades of energy, the two must differ.
TEST(DdfemFit, EachResidualMinimizesItsOwnDataTerm) {
  const FineBlock block = make_fine_block(fiber_ids(), two_materials(1e6, 1e8), kVoxel);
  CoarseFitOptions relative = ddfem_test::small_fit_options();
  relative.regularization = 0;
  relative.heldout_fraction = 0;
  relative.balance_kinds = false;
  relative.kind_weight = {1, 1, 1, 1, 1};
  CoarseFitOptions absolute = relative;
  absolute.residual = CoarseFitOptions::Residual::absolute;
  const ForceSampleSet samples = sample_force_space(block, relative.sampling);
  const std::vector<Vec3> directions = estimate_anisotropy(block, relative.anisotropy).direction;
  const CoarseMaterialFit by_relative = fit_from_samples(block, samples, directions, relative);
  const CoarseMaterialFit by_absolute = fit_from_samples(block, samples, directions, absolute);
  ASSERT_TRUE(by_relative.fitted && by_absolute.fitted);
  struct Terms {
    double absolute = 0, relative = 0;
  };
  auto data_terms = [&](const CoarseMaterialFit& fit) {
    Terms t;
    for (const ForceSample& s : samples.samples) {
      const double V1 =
          coarse_energy(fit, block.coarse_geometry(), block.coarse_rest_positions(), s.corner_displacement);
      if (!std::isfinite(V1)) continue;  // inverted for the coarse element: not fitted by either
      t.absolute += (V1 - s.energy) * (V1 - s.energy);
      t.relative += (V1 - s.energy) * (V1 - s.energy) / (s.energy * s.energy);
    }
    return t;
  };
  const Terms r = data_terms(by_relative), a = data_terms(by_absolute);
  std::printf("[ddfem] fibre block: relative fit %.4e / %.4e, absolute fit %.4e / %.4e (absolute / relative terms)\n",
              r.absolute, r.relative, a.absolute, a.relative);
  EXPECT_LE(a.absolute, r.absolute * (1 + 1e-9));
  EXPECT_LE(r.relative, a.relative * (1 + 1e-9));
  EXPECT_LT(a.absolute, 0.99 * r.absolute);
  EXPECT_LT(r.relative, 0.99 * a.relative);
  EXPECT_EQ(parse_fit_residual("absolute"), CoarseFitOptions::Residual::absolute);
  EXPECT_THROW(parse_fit_residual("squared"), InputError);
}

TEST(DdfemFit, RecoversAKnownAnisotropicCoarseMaterial) {
  // Energies generated by a coarse material with springs: the fit must find
  // it (the regularizer off), and the isotropic model must not manage.
  const auto pal = two_materials(1e6, 1e6);
  const FineBlock block = make_fine_block(BlockMaterials{1, 1, 1, 1, 1, 1, 1, 1}, pal, kVoxel);
  CoarseMaterialFit truth;
  truth.fitted = true;
  std::mt19937_64 rng(9);
  auto u01 = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  const double mu = pal[1]->shear_modulus(), lambda = pal[1]->lame_lambda();
  for (int k = 0; k < 8; ++k) {
    truth.mu[k] = mu * (0.5 + u01());
    truth.lambda[k] = lambda * (0.5 + u01());
    truth.C[k] = k % 2 ? 5 * mu * (0.5 + u01()) : 0.0;
    truth.v[k] = Vec3(1.0, 0.3 * u01(), 0.3 * u01()).normalized();
  }
  const ForceSampleSet set = ddfem_test::samples_of_coarse_material(truth, block, 200, 0.1 * kVoxel, 10);
  for (const ForceSample& s : set.samples) ASSERT_TRUE(std::isfinite(s.energy));
  CoarseFitOptions o;
  o.regularization = 0;
  const CoarseMaterialFit fit = fit_from_samples(block, set, truth.v, o);
  ASSERT_TRUE(fit.fitted);
  EXPECT_LT(fit.heldout_error, 1e-8);
  for (int k = 0; k < 8; ++k) {
    EXPECT_NEAR(fit.mu[k] / truth.mu[k], 1.0, 1e-6) << k;
    EXPECT_NEAR(fit.lambda[k] / truth.lambda[k], 1.0, 1e-6) << k;
    EXPECT_NEAR(fit.C[k], truth.C[k], 1e-6 * mu) << k;
  }
  o.anisotropic = false;
  const CoarseMaterialFit iso = fit_from_samples(block, set, truth.v, o);
  EXPECT_GT(iso.heldout_error, 1e-3);
}

TEST(DdfemFit, CoarseEnergyIsZeroAtRestAndRotationInvariant) {
  const FineBlock block = make_fine_block(layered_ids(), two_materials(1e6, 1e8), kVoxel);
  CoarseFitOptions o = ddfem_test::small_fit_options();
  o.sampling.sphere_directions = 0;
  o.sampling.magnitudes = 1;
  const CoarseMaterialFit f = fit_coarse_material(block, o);
  ASSERT_TRUE(f.fitted);
  const QuadratureMaterials mats = coarse_quadrature_materials(f);
  const hex8::ElementGeometry geo = block.coarse_geometry();
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  EXPECT_NEAR(hex_energy(geo, mats, X), 0.0, 1e-20);
  EXPECT_NEAR(coarse_energy(f, geo, X, Vec24::Zero()), 0.0, 1e-20);

  std::mt19937_64 rng(3);
  auto u01 = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  for (int trial = 0; trial < 5; ++trial) {
    Vec24 u;
    for (int i = 0; i < 24; ++i) u[i] = 0.1 * kVoxel * (2 * u01() - 1);
    hex8::NodeMatrix x = X;
    for (int c = 0; c < 8; ++c) x.row(c) += u.segment<3>(3 * c).transpose();
    const double E = hex_energy(geo, mats, x);
    ASSERT_GT(E, 0.0);
    // The materials reproduce the fitted energy, spring weighting included.
    EXPECT_NEAR(E, coarse_energy(f, geo, X, u), 1e-12 * E);
    const Mat3 R = Eigen::AngleAxisd(3.0 * u01(), Vec3(u01(), u01(), 1.0).normalized()).toRotationMatrix();
    const Vec3 d(u01(), u01(), u01());
    hex8::NodeMatrix moved;
    for (int c = 0; c < 8; ++c) moved.row(c) = (R * x.row(c).transpose() + kVoxel * d).transpose();
    EXPECT_NEAR(hex_energy(geo, mats, moved), E, 1e-9 * E);
  }
}

TEST(DdfemFit, SameSeedGivesIdenticalSamplesAndFit) {
  const FineBlock block = make_fine_block(layered_ids(), two_materials(1e6, 1e7), kVoxel);
  CoarseFitOptions o = ddfem_test::small_fit_options();
  o.sampling.magnitudes = 1;
  o.sampling.seed = 42;
  const ForceSampleSet a = sample_force_space(block, o.sampling);
  const ForceSampleSet b = sample_force_space(block, o.sampling);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  for (size_t s = 0; s < a.samples.size(); ++s) {
    EXPECT_EQ(a.samples[s].energy, b.samples[s].energy);
    EXPECT_EQ(a.samples[s].corner_displacement, b.samples[s].corner_displacement);
  }
  const CoarseMaterialFit fa = fit_coarse_material(block, o);
  const CoarseMaterialFit fb = fit_coarse_material(block, o);
  ASSERT_TRUE(fa.fitted);
  EXPECT_EQ(fa.mu, fb.mu);
  EXPECT_EQ(fa.lambda, fb.lambda);
  EXPECT_EQ(fa.C, fb.C);
  EXPECT_EQ(fa.heldout_error, fb.heldout_error);
  // A different seed turns the sampling directions.
  o.sampling.seed = 43;
  const ForceSampleSet c = sample_force_space(block, o.sampling);
  ASSERT_EQ(a.patterns.size(), c.patterns.size());
  EXPECT_GT((a.patterns[3 * 4].direction - c.patterns[3 * 4].direction).norm(), 1e-3);
}

}  // namespace
}  // namespace msfab

namespace msfab {
namespace {

// Hard cases: contrast 1e4 and nearly incompressible materials (nu = 0.49).
// Every stretching, shearing, bending and twisting sample converges and the
// fit is finite and non-negative; a pinch may have no equilibrium near the
// requested strain (a point load crushing a soft corner element), and such
// samples are dropped and counted, never fitted.
TEST(DdfemFit, ExtremeContrastAndNearIncompressibility) {
  const std::vector<MaterialPtr> pal = {nullptr, std::make_shared<NeoHookean>(1e4, 0.49),
                                        std::make_shared<NeoHookean>(1e8, 0.49)};
  for (const BlockMaterials& ids : {BlockMaterials{1, 2, 1, 2, 1, 2, 1, 2}, BlockMaterials{2, 2, 2, 2, 2, 2, 2, 1}}) {
    const FineBlock block = make_fine_block(ids, pal, kVoxel);
    CoarseFitOptions o = ddfem_test::small_fit_options();
    const ForceSampleSet samples = sample_force_space(block, o.sampling);
    std::array<int, 5> dropped{}, converged{};
    for (const ForceSample& s : samples.samples) ++converged[int(samples.patterns[s.pattern].kind)];
    const int per_pattern = 2 * o.sampling.magnitudes;
    for (const ForcePattern& p : samples.patterns) dropped[int(p.kind)] += per_pattern;
    for (int k = 0; k < 5; ++k) dropped[k] -= converged[k];
    for (int k = 0; k < 4; ++k) EXPECT_EQ(dropped[k], 0) << force_kind_name(ForceKind(k));
    EXPECT_EQ(dropped[4], samples.dropped);
    const std::vector<Vec3> dirs(8, Vec3::UnitX());
    const CoarseMaterialFit fit = fit_from_samples(block, samples, dirs, o);
    ASSERT_TRUE(fit.fitted);
    for (int k = 0; k < 8; ++k) {
      EXPECT_TRUE(std::isfinite(fit.mu[k]) && fit.mu[k] >= 0);
      EXPECT_TRUE(std::isfinite(fit.lambda[k]) && fit.lambda[k] >= 0);
    }
    EXPECT_TRUE(std::isfinite(fit.heldout_error));
    print_fit("contrast 1e4, nu 0.49", fit);
  }
}

}  // namespace
}  // namespace msfab

namespace msfab {
namespace {

// The fit is not tied to 8 points: a 64-point coarse element (the 4-point
// Gauss rule of level 2) on a homogeneous block recovers the material from
// the smooth kinds, and its materials reproduce the fitted energy.
TEST(DdfemFit, SixtyFourPointElementRecoversAHomogeneousMaterial) {
  const auto pal = two_materials(1e6, 1e8);
  const FineBlock block = make_fine_block(BlockMaterials{2, 2, 2, 2, 2, 2, 2, 2}, pal, kVoxel, 4);
  ASSERT_EQ(block.coarse_points(), 64);
  CoarseFitOptions o = ddfem_test::small_fit_options();
  o.kind_weight = {1.0, 1.0, 0.0, 1.0, 0.0};
  const CoarseMaterialFit fit = fit_coarse_material(block, o);
  print_fit("homogeneous, 64 points", fit);
  ASSERT_TRUE(fit.fitted);
  ASSERT_EQ(fit.points(), 64);
  // 192 parameters from 90 training samples: the regularizer (towards the
  // true material) keeps it determined; held-out error seen 2.1%.
  EXPECT_LT(fit.heldout_error, 0.03);
  double mu_mean = 0;
  for (int k = 0; k < 64; ++k) mu_mean += fit.mu[k] / 64;
  EXPECT_NEAR(mu_mean / pal[2]->shear_modulus(), 1.0, 0.02);
  const QuadratureMaterials mats = coarse_quadrature_materials(fit);
  ASSERT_EQ(mats.at_point.size(), 64u);
  const hex8::ElementGeometry geo = block.coarse_geometry();
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  std::mt19937_64 rng(21);
  Vec24 u;
  for (int i = 0; i < 24; ++i) u[i] = 0.05 * kVoxel * (double(rng() >> 11) * 0x1.0p-52 - 1.0);
  hex8::NodeMatrix x = X;
  for (int c = 0; c < 8; ++c) x.row(c) += u.segment<3>(3 * c).transpose();
  const double E = hex_energy(geo, mats, x);
  EXPECT_NEAR(E, coarse_energy(fit, geo, X, u), 1e-12 * E);
  EXPECT_THROW(make_fine_block(BlockMaterials{1, 1, 1, 1, 1, 1, 1, 1}, pal, kVoxel, 3), InputError);
}

}  // namespace
}  // namespace msfab

namespace msfab {
namespace {

TEST(DdfemLevel2Block, PointsMapToTheLevel1PointInTheSameFineVoxel) {
  const double h = kVoxel;  // fine voxel; level-1 children have edge 2h
  const hex8::QuadratureRule r4 = hex8::gauss_rule(4), r2 = hex8::gauss_rule(2);
  for (int q = 0; q < 64; ++q) {
    int c = -1;
    const int k = level1_point_of(q, &c);
    // Positions in the 4h block: level-2 point, and level-1 point k of child c.
    const Vec3 p2 = 2 * h * (r4.points[q] + Vec3::Ones());
    const Vec3 origin(2 * h * (c >> 2 & 1), 2 * h * (c >> 1 & 1), 2 * h * (c & 1));
    const Vec3 p1 = origin + h * (r2.points[k] + Vec3::Ones());
    for (int a = 0; a < 3; ++a) EXPECT_EQ(std::floor(p2[a] / h), std::floor(p1[a] / h)) << q << " axis " << a;
  }
}

TEST(DdfemLevel2Block, BlockOfCoarseMaterialsFitsLikeItsMaterial) {
  // Eight copies of a level-1 material that is exactly a Neo-Hookean one:
  // the level-2 fit on the smooth kinds must recover it at all 64 points.
  const double mu = 4e5, lambda = 9e5;
  const CoarseMaterialFit l1 = ddfem_test::neo_hookean_level1(mu, lambda);
  std::array<const CoarseMaterialFit*, 8> children;
  children.fill(&l1);
  const FineBlock block = make_block_of_coarse_materials(children, BlockMaterials{1, 1, 1, 1, 1, 1, 1, 1}, 2 * kVoxel);
  ASSERT_EQ(block.coarse_points(), 64);
  EXPECT_EQ(block.point_mu0[17], mu);
  CoarseFitOptions o = ddfem_test::small_fit_options();
  o.kind_weight = {1.0, 1.0, 0.0, 1.0, 0.0};
  const CoarseMaterialFit fit = fit_coarse_material(block, o);
  print_fit("level-2 block, homogeneous", fit);
  ASSERT_TRUE(fit.fitted);
  EXPECT_LT(fit.heldout_error, 0.03);
  double mu_mean = 0;
  for (int k = 0; k < 64; ++k) mu_mean += fit.mu[k] / 64;
  EXPECT_NEAR(mu_mean / mu, 1.0, 0.02);
  // Its energy at rest is zero and the children's materials are in place.
  EXPECT_EQ(block.mesh().materials.size(), 8u);
  const ElasticAssembler assembler(block.mesh());
  EXPECT_NEAR(assembler.energy(assembler.rest_positions()), 0.0, 1e-20);

  CoarseMaterialFit unfitted;
  children[3] = &unfitted;
  EXPECT_THROW(make_block_of_coarse_materials(children, BlockMaterials{}, 2 * kVoxel), InputError);
}

}  // namespace
}  // namespace msfab
