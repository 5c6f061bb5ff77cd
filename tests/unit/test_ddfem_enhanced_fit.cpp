// DDFEM coarse materials fitted for the element with condensed bubble modes
// (CoarseFitOptions::enhanced_element, coarse_fit.hpp): the alternation of
// bubbles and parameters finds a known material, the fit no longer trades
// stiffness against bending locking, and what the online element computes
// is what was fitted.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "ddfem/coarse_fit.hpp"
#include "ddfem/fine_block.hpp"
#include "ddfem/level2_block.hpp"
#include "ddfem/periodic_samples.hpp"
#include "ddfem_test_blocks.hpp"
#include "fem/hex8.hpp"
#include "fem/hex_element.hpp"
#include "material/neo_hookean.hpp"

namespace msfab {
namespace {

using ddfem_test::deformed;
using ddfem_test::kVoxel;
using ddfem_test::u01;

// Energies of a known coarse material on the enhanced element: its own
// condensed energies. The alternation starts from the fine materials, far
// from the truth, and must end at it; the trilinear fit of the same data
// cannot match them.
TEST(DdfemEnhancedFit, RecoversAKnownMaterialOnTheEnhancedElement) {
  const auto pal = ddfem_test::two_materials(1e6, 1e6);
  const FineBlock block = make_fine_block(BlockMaterials{1, 1, 1, 1, 1, 1, 1, 1}, pal, kVoxel);
  std::mt19937_64 rng(9);
  CoarseMaterialFit truth;
  truth.fitted = true;
  truth.enhanced = true;
  const double mu = pal[1]->shear_modulus(), lambda = pal[1]->lame_lambda();
  for (int k = 0; k < 8; ++k) {
    truth.mu[k] = mu * (0.3 + u01(rng));
    truth.lambda[k] = lambda * (0.2 + u01(rng));
  }
  const ForceSampleSet set = ddfem_test::samples_of_coarse_material(truth, block, 200, 0.1 * kVoxel, 5);
  for (const ForceSample& s : set.samples) ASSERT_TRUE(std::isfinite(s.energy));
  CoarseFitOptions o;
  o.regularization = 0;
  o.anisotropic = false;
  o.enhanced_element = true;
  o.bubble_rounds = 50;
  const std::vector<Vec3> v(8, Vec3::UnitX());
  const CoarseMaterialFit fit = fit_from_samples(block, set, v, o);
  ASSERT_TRUE(fit.fitted);
  EXPECT_TRUE(fit.enhanced);
  std::printf("[ddfem] enhanced fit of a known material: %d rounds, heldout %.2e\n", fit.bubble_rounds,
              fit.heldout_error);
  EXPECT_LT(fit.bubble_rounds, 50);
  EXPECT_LT(fit.heldout_error, 1e-4);
  for (int k = 0; k < 8; ++k) {
    EXPECT_NEAR(fit.mu[k] / truth.mu[k], 1.0, 1e-3) << k;
    EXPECT_NEAR(fit.lambda[k] / truth.lambda[k], 1.0, 1e-3) << k;
  }
  o.enhanced_element = false;
  const CoarseMaterialFit trilinear = fit_from_samples(block, set, v, o);
  ASSERT_TRUE(trilinear.fitted);
  EXPECT_GT(trilinear.heldout_error, 100 * fit.heldout_error);
}

// A homogeneous nearly incompressible block sampled periodically under
// every force family. The trilinear element locks in bending, so its fit
// softens lambda at every point (docs/ddfem.md, "Centre point"); the
// enhanced element bends without locking, so its fit stays near the block's
// own material and matches the held-out samples better.
TEST(DdfemEnhancedFit, NearlyIncompressibleBlockKeepsItsMaterial) {
  const ddfem_test::NearlyIncompressibleBlock b;
  const auto& pal = b.palette;
  CoarseFitOptions o = b.options;
  const CoarseMaterialFit trilinear = fit_from_samples(b.block, b.samples, b.directions, o);
  o.enhanced_element = true;
  const CoarseMaterialFit enhanced = fit_from_samples(b.block, b.samples, b.directions, o);
  ASSERT_TRUE(trilinear.fitted && enhanced.fitted);
  const double mu = pal[1]->shear_modulus(), lambda = pal[1]->lame_lambda();
  double mu_t = 0, mu_e = 0, lambda_t = 0, lambda_e = 0;
  for (int k = 0; k < 8; ++k) {
    mu_t += trilinear.mu[k] / (8 * mu), mu_e += enhanced.mu[k] / (8 * mu);
    lambda_t += trilinear.lambda[k] / (8 * lambda), lambda_e += enhanced.lambda[k] / (8 * lambda);
  }
  std::printf(
      "[ddfem] nu 0.45 block, trilinear -> enhanced fit: heldout %.4f -> %.4f, mu_k/mu %.3f -> %.3f, "
      "lambda_k/lambda %.3f -> %.3f (%d rounds)\n",
      trilinear.heldout_error, enhanced.heldout_error, mu_t, mu_e, lambda_t, lambda_e, enhanced.bubble_rounds);
  EXPECT_LT(enhanced.heldout_error, 0.7 * trilinear.heldout_error);
  EXPECT_GT(lambda_e, lambda_t + 0.1);
  EXPECT_NEAR(lambda_e, 1.0, 0.15);
  EXPECT_NEAR(mu_e, 1.0, 0.15);
}

// The online element (enhanced geometry, the fit's materials, a centre
// point) stores what coarse_energy says the fit stores, and coarse_energy
// refuses a geometry of the other element.
TEST(DdfemEnhancedFit, OnlineElementIsTheFittedElement) {
  const FineBlock block = make_fine_block(ddfem_test::layered_ids(), ddfem_test::two_materials(1e6, 1e8), kVoxel);
  CoarseFitOptions o = ddfem_test::small_fit_options();
  o.sampling.mode = ForceSamplingOptions::Mode::periodic;
  o.sampling.sphere_directions = 0;
  o.sampling.magnitudes = 1;
  o.centre_point = true;
  o.enhanced_element = true;
  const CoarseMaterialFit f = fit_coarse_material(block, o);
  ASSERT_TRUE(f.fitted);
  ASSERT_TRUE(f.enhanced);
  const QuadratureMaterials mats = coarse_quadrature_materials(f);
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  const hex8::ElementGeometry enhanced = coarse_fit_geometry(X, 8, true);
  const hex8::ElementGeometry geo = coarse_element_geometry(enhanced, X, mats);
  ASSERT_TRUE(geo.has_enhanced_modes());
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 4; ++trial) {
    Vec24 u;
    for (int i = 0; i < 24; ++i) u[i] = 0.1 * kVoxel * (2 * u01(rng) - 1);
    const double online = hex_energy(geo, mats, deformed(X, u));
    EXPECT_NEAR(coarse_energy(f, enhanced, X, u), online, 1e-10 * online);
    // With the bubbles the element stores less than without them.
    const hex8::ElementGeometry plain = coarse_element_geometry(block.coarse_geometry(), X, mats);
    EXPECT_LT(online, hex_energy(plain, mats, deformed(X, u)));
  }
  EXPECT_THROW(coarse_energy(f, block.coarse_geometry(), X, Vec24::Zero()), std::invalid_argument);
}

// What the samples ask of each element, for a homogeneous nu = 0.45 block
// with its own material at every point (periodic sampling): both elements
// store the fine energy of uniform stretching and shearing exactly; in
// bending the trilinear element stores about twice the fine block's energy,
// the enhanced one less than it (the 2 x 2 x 2 fine mesh still locks a
// little). This is the gap every fit of a homogeneous block closes
// (docs/ddfem.md, "Fit on the enhanced element").
TEST(DdfemEnhancedFit, OwnMaterialIsExactInUniformStrainAndCloserInBending) {
  const ddfem_test::NearlyIncompressibleBlock b;
  const auto& pal = b.palette;
  const ForceSampleSet& samples = b.samples;
  CoarseMaterialFit own;
  own.fitted = true;
  for (int k = 0; k < 8; ++k) own.mu[k] = pal[1]->shear_modulus(), own.lambda[k] = pal[1]->lame_lambda();
  const hex8::NodeMatrix X = b.block.coarse_rest_positions();
  double bend[2] = {0, 0};
  int bends = 0;
  for (int enhanced = 0; enhanced < 2; ++enhanced) {
    own.enhanced = enhanced;
    const hex8::ElementGeometry geo = coarse_fit_geometry(X, 8, enhanced);
    for (const ForceSample& s : samples.samples) {
      const ForceKind kind = samples.patterns[s.pattern].kind;
      const double rel = coarse_energy(own, geo, X, s.corner_displacement) / s.energy - 1;
      if (kind == ForceKind::stretch || kind == ForceKind::shear) {
        EXPECT_NEAR(rel, 0.0, 1e-6);
      } else if (kind == ForceKind::bend) {
        bend[enhanced] += rel, bends += enhanced;
      }
    }
  }
  ASSERT_GT(bends, 0);
  bend[0] /= bends, bend[1] /= bends;
  std::printf("[ddfem] nu 0.45 block, own material, bending: coarse/fine energy - 1 = %.3f trilinear, %.3f enhanced\n",
              bend[0], bend[1]);
  EXPECT_GT(bend[0], 0.5);
  EXPECT_LT(bend[1], 0.0);
  EXPECT_LT(std::abs(bend[1]), 0.5 * bend[0]);
}

// A level-2 block of enhanced level-1 materials is sampled as a mesh of
// enhanced elements, the element its children were fitted for.
TEST(DdfemEnhancedFit, Level2BlockOfEnhancedChildrenUsesTheEnhancedElement) {
  CoarseMaterialFit child = ddfem_test::neo_hookean_level1(4e5, 6e5);
  child.enhanced = true;
  std::array<const CoarseMaterialFit*, 8> children;
  children.fill(&child);
  const FineBlock block = make_block_of_coarse_materials(children, BlockMaterials{1, 1, 1, 1, 1, 1, 1, 1}, 2 * kVoxel);
  ASSERT_FALSE(block.voxels.mesh.geometries.empty());
  EXPECT_TRUE(block.voxels.mesh.geometries[0].has_enhanced_modes());
}

}  // namespace
}  // namespace msfab
