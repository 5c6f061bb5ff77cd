// Blocks with void children (docs/ddfem.md, "Blocks with void"): sampled
// among periodic copies, fitted, keyed in a database with void children,
// compressed without the unfitted rows.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/errors.hpp"
#include "ddfem/coarse_db.hpp"
#include "ddfem/db_compression.hpp"
#include "ddfem/hierarchy.hpp"
#include "ddfem/level2_block.hpp"
#include "ddfem/periodic_samples.hpp"
#include "ddfem_test_blocks.hpp"
#include "homog/elastic_tensor.hpp"
#include "homog/periodic_homogenization.hpp"

namespace msfab {
namespace {

using ddfem_test::kVoxel;

// The block repeated periodically is a cell: its 2 x 2 x 2 voxels.
VoxelGrid block_cell(const BlockMaterials& ids) {
  VoxelGrid cell(2, 2, 2, kVoxel, 0);
  for (int c = 0; c < 8; ++c) cell.at(c >> 2 & 1, c >> 1 & 1, c & 1) = ids[c];
  return cell;
}

// Corner displacements of the affine field eps x (eps a Voigt strain).
Vec24 affine_corners(const FineBlock& block, const Vec6& voigt) {
  const Mat3 eps = strain_tensor(voigt);
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  Vec24 u;
  for (int c = 0; c < 8; ++c) u.segment<3>(3 * c) = eps * X.row(c).transpose();
  return u;
}

// Under a small affine strain the relaxed energy of a block among its
// periodic copies is the linear periodic homogenization's 1/2 eps C^H eps
// |Y|, an independent solver (sparse Cholesky on the periodic lattice, void
// as a 1e-9 ersatz). Blocks: one void child; a slab (void above z = h, so
// periodically solid and void layers, which carry nothing across them); two
// children on an edge.
TEST(DdfemVoid, PeriodicBlockEnergyIsTheHomogenizedEnergy) {
  const auto palette = ddfem_test::two_materials(1e5, 1e7);
  const std::vector<BlockMaterials> blocks = {
      {1, 2, 2, 1, 2, 1, 1, 0}, {1, 0, 2, 0, 2, 0, 1, 0}, {2, 2, 0, 0, 0, 0, 0, 0}};
  HomogenizationOptions homog;
  homog.void_stiffness = 1e-9;
  homog.solver = "cholmod";
  for (const BlockMaterials& ids : blocks) {
    const FineBlock block = make_fine_block(ids, palette, kVoxel);
    const PeriodicBlockSolver solver(block);
    const HomogenizationResult H = homogenize(block_cell(ids), palette, homog);
    const double volume = std::pow(2 * kVoxel, 3);
    const double strain = 1e-4;
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> pm1(-1, 1);
    for (int trial = 0; trial < 8; ++trial) {
      Vec6 e;
      for (int m = 0; m < 6; ++m) e[m] = trial < 6 ? (m == trial ? strain : 0.0) : strain * pm1(rng);
      VecX w;
      const double E = solver.relax(affine_corners(block, e), w);
      const double linear = 0.5 * volume * e.dot(H.C * e);
      // The scale of the case: the stiffest phase's energy at this strain.
      const double scale = 0.5 * volume * e.dot(isotropic_tensor(1e7, 0.3) * e);
      SCOPED_TRACE(block_name(ids) + " case " + std::to_string(trial));
      ASSERT_TRUE(std::isfinite(E));
      EXPECT_NEAR(E, linear, 1e-4 * scale + 1e-3 * linear);
    }
  }
}

// A slab (solid below z = h, void above) stretched along x contracts freely
// across its thickness. The sample records the void (upper) corners where
// the relaxed slab puts them, below their prescribed height, and the fitted
// element stores the slab's energy at those corners, as it will in a body
// where nothing holds its upper corners.
TEST(DdfemVoid, SlabRecordsItsRelaxedUpperCornersAndIsFittedThere) {
  const auto palette = ddfem_test::two_materials(1e5, 1e7);
  const BlockMaterials ids = {2, 0, 2, 0, 2, 0, 2, 0};
  const FineBlock block = make_fine_block(ids, palette, kVoxel);
  const PeriodicBlockSolver solver(block);
  Vec6 e = Vec6::Zero();
  e[0] = 0.02;
  const Vec24 u1 = affine_corners(block, e);
  VecX w;
  const double E_fine = solver.relax(u1, w);
  ASSERT_TRUE(std::isfinite(E_fine));
  const Vec24 recorded = solver.corner_displacements(u1, w);
  for (int c = 0; c < 8; ++c) {
    SCOPED_TRACE(c);
    if (c & 1) {
      EXPECT_LT(recorded[3 * c + 2], -0.1 * 0.02 * 2 * kVoxel) << "an upper corner contracts";
    } else {
      EXPECT_EQ(recorded.segment<3>(3 * c), u1.segment<3>(3 * c)) << "a corner with a node keeps its value";
    }
  }
  CoarseFitOptions options = ddfem_test::small_fit_options();
  options.sampling.mode = ForceSamplingOptions::Mode::periodic;
  const CoarseMaterialFit fit = fit_coarse_material(block, options);
  ASSERT_TRUE(fit.fitted) << fit.not_fitted_reason;
  EXPECT_GT(fit.samples_train, 10);
  EXPECT_GT(fit.samples_dropped, 0) << "straining across the void layers stores no energy";
  const double E_coarse = coarse_energy(fit, block.coarse_geometry(), block.coarse_rest_positions(), recorded);
  EXPECT_NEAR(E_coarse, E_fine, 0.3 * E_fine);
}

// A fit of a block with void children must keep some stiffness in every
// uniform strain: the block's own fine materials do; a fit with mu = 0 at
// every point (bulk only) has none in shear and is refused.
TEST(DdfemVoid, FitsWithoutShearStiffnessAreRefused) {
  const auto palette = ddfem_test::two_materials(1e5, 1e7);
  const FineBlock block = make_fine_block({2, 1, 0, 2, 0, 0, 1, 2}, palette, kVoxel);
  CoarseMaterialFit fit(8);
  fit.fitted = true;
  for (int k = 0; k < 8; ++k) {
    fit.mu0[k] = fit.mu[k] = block.point_mu0[k];
    fit.lambda0[k] = fit.lambda[k] = block.point_lambda0[k];
  }
  EXPECT_TRUE(fit_resists_uniform_strains(fit, block));
  for (int k = 0; k < 8; ++k) fit.mu[k] *= 1e-2;
  EXPECT_TRUE(fit_resists_uniform_strains(fit, block));
  for (int k = 0; k < 8; ++k) fit.mu[k] = 0.0;
  EXPECT_FALSE(fit_resists_uniform_strains(fit, block));
  // A spring along x gives stiffness in xx and in the shears that turn x,
  // not in yz.
  for (int k = 0; k < 8; ++k) fit.C[k] = 1e7, fit.v[k] = Vec3::UnitX();
  EXPECT_FALSE(fit_resists_uniform_strains(fit, block));
}

// A database with void children keys every combination with a solid child;
// codes round-trip, and the all-void block has none.
TEST(DdfemVoid, CombinationCodesIncludeVoidChildren) {
  CoarseDatabase db;
  db.materials = {{"a", 1e5, 0.3, 1000}, {"b", 1e7, 0.3, 1000}};
  EXPECT_EQ(db.num_combinations(), 256);
  EXPECT_EQ(db.combination_code({1, 0, 1, 1, 1, 1, 1, 1}), -1);
  db.void_children = true;
  EXPECT_EQ(db.num_combinations(), 6561);
  EXPECT_EQ(db.combination_code({0, 0, 0, 0, 0, 0, 0, 0}), 0);
  std::mt19937_64 rng(3);
  for (int t = 0; t < 100; ++t) {
    BlockMaterials ids;
    for (int& id : ids) id = static_cast<int>(rng() % 3);
    const std::int64_t code = db.combination_code(ids);
    ASSERT_GE(code, 0);
    ASSERT_LT(code, 6561);
    EXPECT_EQ(db.combination_ids(code), ids);
  }
  EXPECT_EQ(db.combination_code({3, 0, 0, 0, 0, 0, 0, 0}), -1);
}

// Compression takes the fitted rows only; unfitted ones (the all-void block,
// blocks without usable samples) map to no representative.
TEST(DdfemVoid, CompressionSkipsUnfittedRows) {
  CoarseDatabase db;
  db.materials = {{"a", 1e5, 0.3, 1000}};
  db.void_children = true;
  const std::int64_t N = db.num_combinations();  // 256
  db.entries.resize(N);
  db.entry_of.resize(N);
  db.orbit.resize(N);
  for (std::int64_t c = 0; c < N; ++c) {
    db.entry_of[c] = static_cast<int>(c);
    db.orbit[c] = static_cast<int>(c);
    CoarseMaterialFit& fit = db.entries[c];
    fit.material_ids = db.combination_ids(c);
    int solid = 0;
    for (int id : fit.material_ids) solid += id != 0;
    fit.fitted = solid >= 2;  // the all-void and one-child blocks "not fitted"
    for (int k = 0; k < 8; ++k) fit.mu[k] = fit.lambda[k] = fit.fitted ? 1e4 * (1 + solid) : 0.0;
  }
  db.entry_of[0] = -1;
  const CoarseDatabase small = compress_database(db, 5, 16, 0.05, 1);
  ASSERT_EQ(small.entries.size(), 5u);
  for (const CoarseMaterialFit& fit : small.entries) EXPECT_TRUE(fit.fitted);
  for (std::int64_t c = 0; c < N; ++c) {
    if (db.entries[c].fitted && db.entry_of[c] >= 0)
      EXPECT_GE(small.entry_of[c], 0) << c;
    else
      EXPECT_EQ(small.entry_of[c], -1) << c;
  }
  EXPECT_EQ(small.find({0, 0, 0, 0, 0, 0, 0, 1}), nullptr);
  EXPECT_NE(small.find({0, 0, 0, 0, 0, 0, 1, 1}), nullptr);
}

// A level-2 block whose level-1 children are exactly Neo-Hookean at their 8
// Gauss points is the same finite element model as a fine block of those
// materials at twice the voxel size, void children included: the relaxed
// periodic energies agree to round-off.
TEST(DdfemVoid, Level2BlockWithVoidChildrenIsTheFineBlockAtTwiceTheSize) {
  const auto palette = ddfem_test::two_materials(1e5, 1e7);
  const BlockMaterials ids = {2, 1, 0, 2, 0, 0, 1, 2};
  std::array<CoarseMaterialFit, 3> level1;
  for (int m = 1; m <= 2; ++m)
    level1[m] = ddfem_test::neo_hookean_level1(palette[m]->shear_modulus(), palette[m]->lame_lambda());
  std::array<const CoarseMaterialFit*, 8> children;
  for (int c = 0; c < 8; ++c) children[c] = ids[c] ? &level1[ids[c]] : nullptr;
  const FineBlock level2 = make_block_of_coarse_materials(children, ids, 2 * kVoxel);
  const FineBlock fine = make_fine_block(ids, palette, 2 * kVoxel);
  ASSERT_EQ(level2.mesh().num_elements(), 5);
  const PeriodicBlockSolver a(level2), b(fine);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> pm1(-1, 1);
  for (int trial = 0; trial < 4; ++trial) {
    Vec24 u;
    for (int i = 0; i < 24; ++i) u[i] = 0.02 * 4 * kVoxel * pm1(rng);
    VecX wa, wb;
    const double Ea = a.relax(u, wa), Eb = b.relax(u, wb);
    ASSERT_TRUE(std::isfinite(Ea));
    EXPECT_NEAR(Ea, Eb, 1e-9 * Eb);
    EXPECT_TRUE((a.corner_displacements(u, wa) - b.corner_displacements(u, wb)).norm() < 1e-9 * u.norm());
  }
  const std::array<const CoarseMaterialFit*, 8> none{};
  EXPECT_THROW(make_block_of_coarse_materials(none, BlockMaterials{}, 2 * kVoxel), InputError);
}

// With the all-void child as one more input, a hierarchy that keeps every
// candidate looks every arrangement of two materials and void up to itself,
// and the all-void and solid/void layered cells are seeds.
TEST(DdfemVoid, HierarchyWithAVoidInputLooksArrangementsUpExactly) {
  std::vector<CoarseMaterialFit> level1 = {ddfem_test::neo_hookean_level1(3.4e4, 3.1e5),
                                           ddfem_test::neo_hookean_level1(3.4e6, 3.1e7)};
  for (int m = 0; m < 2; ++m) level1[m].material_ids.fill(m + 1);
  HierarchyOptions o;
  o.representatives = {9, 81, 6561};
  o.deformations = 8;
  const Level2Hierarchy h = build_level2_hierarchy(level1, 2 * kVoxel, o, true);
  EXPECT_EQ(h.level1_entries(), 2);
  EXPECT_EQ(h.void_entry(), 2);
  ASSERT_EQ(h.num_final(), 6561);
  std::mt19937_64 rng(4);
  for (int t = 0; t < 300; ++t) {
    Arrangement e;
    for (int& x : e) x = static_cast<int>(rng() % 3);
    ASSERT_EQ(h.arrangement(2, h.lookup(e)), e);
  }
  // Compressed: the seeds survive (all void; a stiff slab under void).
  o.representatives = {5, 8, 12};
  const Level2Hierarchy small = build_level2_hierarchy(level1, 2 * kVoxel, o, true);
  Arrangement all_void, slab;
  all_void.fill(2);
  for (int c = 0; c < 8; ++c) slab[c] = (c & 1) ? 2 : 1;
  EXPECT_EQ(small.arrangement(2, small.lookup(all_void)), all_void);
  EXPECT_EQ(small.arrangement(2, small.lookup(slab)), slab);
}

}  // namespace
}  // namespace msfab
