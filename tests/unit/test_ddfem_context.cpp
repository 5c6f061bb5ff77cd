// DDFEM in-situ sampling: a block surrounded by its own periodic copies,
// loaded by stress fields on the patch's outer faces (docs/ddfem.md,
// "In-situ sampling").
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/errors.hpp"
#include "ddfem/anisotropy.hpp"
#include "ddfem/coarse_fit.hpp"
#include "ddfem/fine_block.hpp"
#include "ddfem/force_samples.hpp"
#include "ddfem/level2_block.hpp"
#include "ddfem/periodic_samples.hpp"
#include "ddfem_test_blocks.hpp"
#include "fem/elastic_assembler.hpp"
#include "material/neo_hookean.hpp"

namespace msfab {
namespace {

using ddfem_test::kVoxel;
using ddfem_test::layered_ids;
using ddfem_test::two_materials;

// Worst relative difference, over the stretch and shear samples of a set,
// between the sample's energy and the coarse energy of `exact` at its
// corner displacements; *checked counts them.
double worst_affine_energy_error(const ForceSampleSet& set, const CoarseMaterialFit& exact, const FineBlock& b,
                                 int* checked) {
  double worst = 0;
  *checked = 0;
  for (const ForceSample& s : set.samples) {
    const ForceKind kind = set.patterns[s.pattern].kind;
    if (kind != ForceKind::stretch && kind != ForceKind::shear) continue;
    const double V1 = coarse_energy(exact, b.coarse_geometry(), b.coarse_rest_positions(), s.corner_displacement);
    worst = std::max(worst, std::abs(V1 - s.energy) / s.energy);
    ++*checked;
  }
  return worst;
}

// The coarse material of a homogeneous Neo-Hookean block: (mu, lambda) at
// every point, no springs.
CoarseMaterialFit homogeneous_fit(int points, double mu, double lambda) {
  CoarseMaterialFit fit(points);
  fit.fitted = true;
  for (int k = 0; k < points; ++k) fit.mu[k] = mu, fit.lambda[k] = lambda;
  return fit;
}

TEST(DdfemContext, PatchOfPeriodicCopies) {
  const auto pal = two_materials(1e6, 1e8);
  BlockMaterials ids{1, 2, 2, 1, 2, 1, 1, 2};
  const FineBlock b = make_fine_block(ids, pal, kVoxel, 2, 1);
  EXPECT_EQ(b.mesh().num_elements(), 64);
  EXPECT_EQ(b.mesh().num_nodes(), 125);
  int core = 0;
  for (char c : b.core_element) core += c;
  EXPECT_EQ(core, 8);
  for (int c = 0; c < 8; ++c) {
    ASSERT_GE(b.corner_nodes[c], 0);
    const Vec3 p = b.mesh().nodes.row(b.corner_nodes[c]).transpose();
    EXPECT_NEAR((p - b.coarse_rest_positions().row(c).transpose()).norm(), 0.0, 1e-15);
  }
  // Every element carries its child's material, and a voxel two voxels away
  // (one period) carries the same one.
  for (int e = 0; e < b.mesh().num_elements(); ++e) {
    const Vec3 mid =
        0.5 * (b.mesh().element_rest_positions(e).row(0) + b.mesh().element_rest_positions(e).row(7)).transpose();
    const int i = static_cast<int>(std::floor(mid.x() / kVoxel)), j = static_cast<int>(std::floor(mid.y() / kVoxel)),
              k = static_cast<int>(std::floor(mid.z() / kVoxel));
    const int child = 4 * ((i % 2 + 2) % 2) + 2 * ((j % 2 + 2) % 2) + ((k % 2 + 2) % 2);
    EXPECT_EQ(b.child_of_element(e), child);
    EXPECT_EQ(b.mesh().element_tag[e], ids[child]);
    EXPECT_EQ(b.core_element[e] != 0, i >= 0 && i < 2 && j >= 0 && j < 2 && k >= 0 && k < 2);
  }
  EXPECT_THROW(make_fine_block(ids, pal, kVoxel, 2, 5), InputError);
  EXPECT_THROW(make_fine_block(ids, pal, kVoxel, 2, -1), InputError);
}

TEST(DdfemContext, OuterFaceLoadsAreSelfEquilibratedAndKeepTheirKinds) {
  const auto pal = two_materials(1e6, 1e8);
  const FineBlock b = make_fine_block(layered_ids(), pal, kVoxel, 2, 1);
  ForceSamplingOptions o;
  o.sphere_directions = 2;
  const auto patterns = make_force_patterns(b, o);
  ASSERT_EQ(patterns.size(), 5u * 4u + 12u);
  const BlockSolver solver(b);
  ASSERT_TRUE(solver.sparse());
  for (const ForcePattern& p : patterns) {
    EXPECT_NEAR(p.force.norm(), 1.0, 1e-12);
    EXPECT_LT((solver.constraint_matrix() * p.force).norm(), 1e-12);  // net force and moment
    if (p.kind == ForceKind::pinch) continue;
    // Nothing acts inside the patch: loaded nodes lie on its outer faces.
    const Vec3 lo = b.mesh().bbox_min(), hi = b.mesh().bbox_max();
    for (int i = 0; i < b.mesh().num_nodes(); ++i) {
      const Vec3 X = b.mesh().nodes.row(i).transpose();
      const bool outer = ((X - lo).cwiseAbs().minCoeff() < 1e-12) || ((X - hi).cwiseAbs().minCoeff() < 1e-12);
      if (!outer) {
        EXPECT_LT(p.force.segment<3>(3 * i).norm(), 1e-14);
      }
    }
  }
}

// The sparse KKT Newton: the solution satisfies the rigid-motion
// constraints and is in equilibrium up to a reaction the constraints carry
// (which is zero for a self-equilibrated load).
TEST(DdfemContext, SparseNewtonSolvesTheConstrainedProblem) {
  const auto pal = two_materials(1e5, 1e7);
  const FineBlock b = make_fine_block(BlockMaterials{1, 2, 2, 1, 2, 1, 1, 2}, pal, kVoxel, 2, 1);
  const BlockSolver solver(b, 1e-10);
  ForceSamplingOptions o;
  o.sphere_directions = 1;
  for (const ForcePattern& p : make_force_patterns(b, o)) {
    if (p.kind == ForceKind::pinch) continue;
    const double load = 0.1 / solver.linear_peak_strain(p.force);
    const auto s = solver.solve(load * p.force);
    ASSERT_TRUE(s.converged) << force_kind_name(p.kind);
    const VecX u = s.x - solver.assembler().rest_positions();
    EXPECT_LT((solver.constraint_matrix() * u).norm(), 1e-12 * kVoxel);
    VecX g(u.size());
    solver.assembler().evaluate(s.x, &g, nullptr);
    const MatX& G = solver.constraint_matrix();
    const VecX r = g - load * p.force;
    const VecX reaction = G.transpose() * (G * G.transpose()).ldlt().solve(G * r);
    EXPECT_LT((r - reaction).norm(), 1e-8 * load) << force_kind_name(p.kind);
    EXPECT_GT(s.energy, 0.0);
    EXPECT_LT(s.energy, solver.assembler().energy(s.x));  // the block's share of the patch energy
  }
}

// A homogeneous block in context deforms affinely under the constant
// stress fields, so each stretch and shear sample is exactly a coarse
// element of the block's own material under that deformation.
TEST(DdfemContext, HomogeneousBlockIsReproducedExactly) {
  const auto pal = two_materials(1e6, 1e8);
  const FineBlock b = make_fine_block(BlockMaterials{2, 2, 2, 2, 2, 2, 2, 2}, pal, kVoxel, 2, 1);
  ForceSamplingOptions o;
  o.sphere_directions = 3;
  o.magnitudes = 3;
  const ForceSampleSet set = sample_force_space(b, o);
  EXPECT_EQ(set.dropped, 0);
  int checked = 0;
  const double worst =
      worst_affine_energy_error(set, homogeneous_fit(8, pal[2]->shear_modulus(), pal[2]->lame_lambda()), b, &checked);
  std::printf("[ddfem-context] homogeneous block: %d stretch/shear samples, worst relative energy difference %.2e\n",
              checked, worst);
  EXPECT_EQ(checked, 2 * 2 * 3 * 6);  // 2 kinds x 2 signs x 3 magnitudes x 6 directions
  EXPECT_LT(worst, 1e-8);
  // The isolated block loaded by lumped body forces is not affine in general.
  const FineBlock isolated = make_fine_block(BlockMaterials{2, 2, 2, 2, 2, 2, 2, 2}, pal, kVoxel);
  EXPECT_FALSE(BlockSolver(isolated).sparse());
}

// Uniaxial strain energy density of the coarse element of a fit, at small
// strain eps along axis a: C_aaaa eps^2 / 2.
double coarse_axial_modulus(const CoarseMaterialFit& fit, const FineBlock& b, int a) {
  const double eps = 1e-4;
  Vec24 u = Vec24::Zero();
  const auto X = b.coarse_rest_positions();
  for (int c = 0; c < 8; ++c) u[3 * c + a] = eps * X(c, a);
  const double V = coarse_energy(fit, b.coarse_geometry(), X, u);
  const double volume = std::pow(2 * kVoxel, 3);
  return 2 * V / (volume * eps * eps);
}

// A layered block: the fitted axial stiffness along the layers lies
// between the Reuss and Voigt bounds of the two materials, and in context
// (where the stiff layer continues through the block's faces, as in a body)
// it is closer to Voigt than when the block is sampled alone.
TEST(DdfemContext, LayeredBlockMovesTowardVoigtAlongTheLayers) {
  const auto pal = two_materials(1e5, 1e7);
  const double M_soft = pal[1]->lame_lambda() + 2 * pal[1]->shear_modulus();
  const double M_stiff = pal[2]->lame_lambda() + 2 * pal[2]->shear_modulus();
  const double voigt = 0.5 * (M_soft + M_stiff), reuss = 2.0 / (1.0 / M_soft + 1.0 / M_stiff);
  CoarseFitOptions options = ddfem_test::small_fit_options();
  options.sampling.magnitudes = 1;  // patch sampling is the slow mode; one magnitude shows the move
  const FineBlock alone = make_fine_block(layered_ids(), pal, kVoxel);
  const FineBlock in_context = make_fine_block(layered_ids(), pal, kVoxel, 2, 1);
  const CoarseMaterialFit fit_alone = fit_coarse_material(alone, options);
  options.sampling.mode = ForceSamplingOptions::Mode::patch;
  const CoarseMaterialFit fit_patch = fit_coarse_material(in_context, options);
  options.sampling.mode = ForceSamplingOptions::Mode::periodic;
  const CoarseMaterialFit fit_periodic = fit_coarse_material(alone, options);
  ASSERT_TRUE(fit_alone.fitted);
  ASSERT_TRUE(fit_patch.fitted);
  ASSERT_TRUE(fit_periodic.fitted);
  auto along = [&](const CoarseMaterialFit& fit, const FineBlock& b) {  // x and y lie in the layers
    return 0.5 * (coarse_axial_modulus(fit, b, 0) + coarse_axial_modulus(fit, b, 1));
  };
  const double along_alone = along(fit_alone, alone);
  for (const auto* fit : {&fit_patch, &fit_periodic}) {
    const double along_context = along(*fit, alone);
    const double across_context = coarse_axial_modulus(*fit, alone, 2);
    std::printf(
        "[ddfem-context] layered block, axial modulus / Voigt: along layers alone %.3f, in context (%s) "
        "%.3f; across in context %.3f; Reuss %.3f\n",
        along_alone / voigt, fit == &fit_patch ? "patch" : "periodic", along_context / voigt, across_context / voigt,
        reuss / voigt);
    EXPECT_GT(along_context, along_alone * 1.2);
    EXPECT_GT(along_context, reuss);
    EXPECT_LT(along_context, voigt * 1.05);
    EXPECT_LT(across_context, along_context);  // layers are soft across
  }
}

// Periodic (kinematic) sampling of a homogeneous block: affine corner
// displacements leave the fluctuation at zero, so stretch and shear
// samples are exactly the coarse element of the block's material; for the
// non-affine families the relaxed energy is a minimum over the fluctuation.
TEST(DdfemPeriodic, HomogeneousBlockIsExactAndTheFluctuationMinimizes) {
  const auto pal = two_materials(1e6, 1e8);
  const FineBlock b = make_fine_block(BlockMaterials{2, 2, 2, 2, 2, 2, 2, 2}, pal, kVoxel);
  ForceSamplingOptions o;
  o.sphere_directions = 3;
  o.magnitudes = 3;
  const ForceSampleSet set = sample_periodic(b, o);
  EXPECT_EQ(set.dropped, 0);
  EXPECT_EQ(set.attempted, (6 * 4 + 12) * 2 * 3);
  int checked = 0;
  EXPECT_LT(
      worst_affine_energy_error(set, homogeneous_fit(8, pal[2]->shear_modulus(), pal[2]->lame_lambda()), b, &checked),
      1e-12);
  // Relaxed bending: below the unrelaxed (w = 0) energy, and a minimum.
  const PeriodicBlockSolver solver(b, 1e-12);
  const ElasticAssembler assembler(b.mesh());
  int relaxed = 0;
  for (const ForcePattern& p : set.patterns) {
    if (p.kind != ForceKind::bend && p.kind != ForceKind::twist) continue;
    const Vec24 u1 = 0.05 * Vec24(p.force);
    VecX w;
    const double E = solver.relax(u1, w);
    ASSERT_TRUE(std::isfinite(E));
    const double unrelaxed = assembler.energy(solver.positions(u1, VecX::Zero(21)));
    EXPECT_LE(E, unrelaxed * (1 + 1e-13));
    relaxed += E < unrelaxed * (1 - 1e-6);
    for (int trial = 0; trial < 4; ++trial) {
      VecX dw = VecX::Zero(21);
      dw[(5 * trial + 2) % 21] = 1e-6 * kVoxel, dw[(7 * trial + 11) % 21] = -0.5e-6 * kVoxel;
      EXPECT_GE(assembler.energy(solver.positions(u1, w + dw)), E * (1 - 1e-13));
      EXPECT_GE(assembler.energy(solver.positions(u1, w - dw)), E * (1 - 1e-13));
    }
    // The corners are exactly the prescribed displacements.
    const VecX x = solver.positions(u1, w);
    for (int c = 0; c < 8; ++c) {
      const int n = b.corner_nodes[c];
      EXPECT_LT((x.segment<3>(3 * n) - b.mesh().nodes.row(n).transpose() - u1.segment<3>(3 * c)).norm(), 1e-18);
    }
  }
  EXPECT_GT(relaxed, 0);  // the axis-aligned modes need no fluctuation by symmetry; the oblique ones do
}

// A fibre block (stiff column along y through the block, periodic copies
// make it continuous): periodic sampling fits a clearly larger axial
// stiffness along the fibre than isolated force sampling. Both stay well
// below the rule of mixtures: one isotropic point plus one spring per Gauss
// point cannot be stiff along the fibre and soft across it at once
// (docs/ddfem.md, "In-situ sampling").
TEST(DdfemPeriodic, FiberBlockCarriesLoadAlongTheFiber) {
  const auto pal = two_materials(1e5, 1e7);
  BlockMaterials ids;
  for (int c = 0; c < 8; ++c) ids[c] = ((c >> 2 & 1) == 0 && (c & 1) == 0) ? 2 : 1;  // x = 0, z = 0: one column
  const FineBlock b = make_fine_block(ids, pal, kVoxel);
  CoarseFitOptions options = ddfem_test::small_fit_options();
  const CoarseMaterialFit alone = fit_coarse_material(b, options);
  options.sampling.mode = ForceSamplingOptions::Mode::periodic;
  const CoarseMaterialFit periodic = fit_coarse_material(b, options);
  const double M_soft = pal[1]->lame_lambda() + 2 * pal[1]->shear_modulus();
  const double M_stiff = pal[2]->lame_lambda() + 2 * pal[2]->shear_modulus();
  const double voigt = 0.25 * M_stiff + 0.75 * M_soft;
  const double E_alone = coarse_axial_modulus(alone, b, 1), E_periodic = coarse_axial_modulus(periodic, b, 1);
  std::printf("[ddfem-periodic] fibre block, axial modulus along the fibre / Voigt: isolated %.3f, periodic %.3f\n",
              E_alone / voigt, E_periodic / voigt);
  EXPECT_GT(E_periodic, 2.0 * E_alone);
  EXPECT_LT(E_periodic, 1.05 * voigt);
}

// Level 2: a block of eight level-1 coarse materials, here eight copies of
// one exactly Neo-Hookean material. In a patch each context element takes
// its child's material, and both in-situ modes reproduce the material on
// the affine families to round-off (the 64-point coarse element of a
// homogeneous block under a uniform deformation).
TEST(DdfemContext, Level2BlockInContextAndPeriodic) {
  const double mu = 4e5, lambda = 9e5;
  const CoarseMaterialFit l1 = ddfem_test::neo_hookean_level1(mu, lambda);
  std::array<const CoarseMaterialFit*, 8> children;
  children.fill(&l1);
  const FineBlock patch =
      make_block_of_coarse_materials(children, BlockMaterials{1, 2, 3, 4, 5, 6, 7, 8}, 2 * kVoxel, 1);
  ASSERT_EQ(patch.mesh().num_elements(), 64);
  for (int e = 0; e < 64; ++e) {
    EXPECT_EQ(patch.mesh().element_material[e], patch.child_of_element(e));
    EXPECT_EQ(patch.mesh().element_tag[e], patch.child_of_element(e) + 1);
  }
  const FineBlock alone = make_block_of_coarse_materials(children, BlockMaterials{1, 2, 3, 4, 5, 6, 7, 8}, 2 * kVoxel);
  ForceSamplingOptions o;
  o.sphere_directions = 1;
  o.magnitudes = 2;
  for (const FineBlock* b : {&patch, &alone}) {
    const ForceSampleSet set = b == &patch ? sample_force_space(*b, o) : sample_periodic(*b, o);
    EXPECT_EQ(set.dropped, 0);
    int checked = 0;
    const double worst = worst_affine_energy_error(set, homogeneous_fit(64, mu, lambda), *b, &checked);
    EXPECT_EQ(checked, 2 * 2 * 2 * 4);
    EXPECT_LT(worst, 1e-8) << (b == &patch ? "patch" : "periodic");
  }
}

// fit.mixed_affine_only: a mixed block is fitted on its stretch and shear
// samples alone (as with zero bend, twist and pinch weights), a block of one
// material on all of them (as without the option), on identical samples.
TEST(DdfemPeriodic, MixedBlocksAffineOnlyDropsTheNonAffineSamplesOfMixedBlocks) {
  const auto pal = two_materials(1e5, 1e7);
  CoarseFitOptions options = ddfem_test::small_fit_options();
  options.sampling.mode = ForceSamplingOptions::Mode::periodic;
  CoarseFitOptions flagged = options;
  flagged.mixed_blocks_affine_only = true;
  CoarseFitOptions affine = options;
  for (ForceKind k : {ForceKind::bend, ForceKind::twist, ForceKind::pinch}) affine.kind_weight[int(k)] = 0.0;
  auto parameters = [](const CoarseMaterialFit& f) {
    std::vector<double> p;
    for (int k = 0; k < f.points(); ++k) p.insert(p.end(), {f.mu[k], f.lambda[k], f.C[k]});
    return p;
  };
  for (const BlockMaterials& ids : {ddfem_test::layered_ids(), BlockMaterials{2, 2, 2, 2, 2, 2, 2, 2}}) {
    const bool mixed = ids[0] != ids[1];
    const FineBlock b = make_fine_block(ids, pal, kVoxel);
    const ForceSampleSet samples = sample_periodic(b, options.sampling);
    const std::vector<Vec3> directions = estimate_anisotropy(b, options.anisotropy).direction;
    const CoarseMaterialFit with_flag = fit_from_samples(b, samples, directions, flagged);
    const CoarseMaterialFit all = fit_from_samples(b, samples, directions, options);
    const CoarseMaterialFit affine_only = fit_from_samples(b, samples, directions, affine);
    ASSERT_TRUE(with_flag.fitted && all.fitted && affine_only.fitted);
    EXPECT_EQ(parameters(with_flag), parameters(mixed ? affine_only : all)) << (mixed ? "mixed" : "uniform");
    double largest_change = 0;
    const auto a = parameters(all), f = parameters(affine_only);
    for (size_t i = 0; i < a.size(); ++i)
      largest_change = std::max(largest_change, std::abs(a[i] - f[i]) / pal[1]->shear_modulus());
    EXPECT_GT(largest_change, 1e-3) << "the non-affine samples must matter for the test to mean anything";
  }
}

}  // namespace
}  // namespace msfab
