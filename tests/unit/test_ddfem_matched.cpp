// Matched coarsening (ddfem/matched_coarsening.hpp): naive per-point
// materials carried by one congruence onto the block's homogenized C^H.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <random>

#include "core/errors.hpp"
#include "ddfem/baseline_coarsening.hpp"
#include "ddfem/matched_coarsening.hpp"
#include "ddfem/voxel_coarsening.hpp"
#include "ddfem/windowed_stiffness.hpp"
#include "material/green_anisotropic.hpp"
#include "material/neo_hookean.hpp"
#include "material/voigt.hpp"

using namespace msfab;

namespace {

std::vector<MaterialPtr> three_materials() {
  return {nullptr, std::make_shared<NeoHookean>(1e5, 0.45), std::make_shared<NeoHookean>(1e6, 0.45),
          std::make_shared<NeoHookean>(1e7, 0.45)};
}

std::vector<int> random_block(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<int> ids(n * n * n);
  for (int& id : ids) id = 1 + static_cast<int>(rng() % 3);
  return ids;
}

}  // namespace

TEST(MatchedCoarsening, UniformResponseEqualsTheAssembledElements) {
  // The condensation of uniform_strain_response against U^T K U / V of the
  // element assembled by hex_evaluate (bubbles condensed by its Newton), on
  // both elements, a stretched box and random anisotropic point stiffnesses.
  std::mt19937_64 rng(11);
  hex8::NodeMatrix X;
  for (int c = 0; c < 8; ++c) X.row(c) = Vec3(2.0 * (c >> 2 & 1), 1.0 * (c >> 1 & 1), 0.5 * (c & 1)).transpose();
  for (bool enhanced : {false, true}) {
    const hex8::QuadratureRule rule = hex8::gauss_rule(enhanced ? 4 : 2);
    const hex8::ElementGeometry geo =
        enhanced ? hex8::enhanced_element_geometry(X, rule) : hex8::element_geometry(X, rule);
    std::vector<Mat6> C;
    QuadratureMaterials m;
    for (int q = 0; q < geo.size(); ++q) {
      Mat6 R;
      for (int i = 0; i < 36; ++i) R.data()[i] = double(rng() >> 11) * 0x1.0p-53 - 0.5;
      C.push_back(1e6 * (R * R.transpose() + 0.1 * Mat6::Identity()));
      m.at_point.push_back(std::make_shared<GreenAnisotropic>(C.back()));
    }
    Mat24 K;
    hex_evaluate(geo, m, X, nullptr, &K);
    Eigen::Matrix<double, 24, 6> U;
    for (int i = 0; i < 6; ++i)
      for (int c = 0; c < 8; ++c) U.block<3, 1>(3 * c, i) = voigt_to_strain(Vec6::Unit(i)) * X.row(c).transpose();
    const Mat6 assembled = U.transpose() * K * U / (2.0 * 1.0 * 0.5);
    EXPECT_LE((uniform_strain_response(geo, C) - assembled).norm(), 1e-9 * assembled.norm()) << "enhanced " << enhanced;
  }
}

TEST(MatchedCoarsening, TrilinearResponseIsTheHomogenizedStiffnessAfterOneStep) {
  const auto palette = three_materials();
  for (int n : {2, 4}) {
    const std::vector<int> ids = random_block(n, 17 + n);
    int iterations = -1;
    double residual = -1;
    const std::vector<Mat6> C = matched_point_stiffness(palette, ids, n, false, &iterations, &residual);
    const Mat6 CH = block_homogenized_stiffness(palette, ids, n);
    // On the trilinear element the response is linear in the C_q: one
    // congruence lands on C^H to round-off.
    EXPECT_LE((element_uniform_response(C, n, false) - CH).norm(), 1e-9 * CH.norm()) << "n = " << n;
    EXPECT_EQ(iterations, 1);
    EXPECT_LE(residual, 1e-9);
  }
}

TEST(MatchedCoarsening, EnhancedResponseConvergesToTheHomogenizedStiffness) {
  const auto palette = three_materials();
  const std::vector<int> ids = random_block(4, 5);
  double residual = -1;
  const std::vector<Mat6> C = matched_point_stiffness(palette, ids, 4, true, nullptr, &residual);
  const Mat6 CH = block_homogenized_stiffness(palette, ids, 4);
  const double r = (element_uniform_response(C, 4, true) - CH).norm() / CH.norm();
  EXPECT_LE(r, 1e-6);
  EXPECT_NEAR(r, residual, 1e-12);
}

TEST(MatchedCoarsening, NaivePointsOnTheEnhancedElementAlreadyHaveTheCellsStiffnessAtLevel1) {
  // docs/ddfem.md: on the enhanced element one naive point per child of a
  // 2 x 2 x 2 block responds to uniform strains with the block's periodic
  // C^H, so matched materials equal naive ones at level 1; at level 2 they
  // do not.
  const auto palette = three_materials();
  for (std::uint64_t seed : {1, 2, 3}) {
    for (int n : {2, 4}) {
      const std::vector<int> ids = random_block(n, seed);
      std::vector<Mat6> C;
      for (int id : ids) C.push_back(rest_voigt_stiffness(*palette[id]));
      const Mat6 CH = block_homogenized_stiffness(palette, ids, n);
      const double gap = (element_uniform_response(C, n, true) - CH).norm() / CH.norm();
      if (n == 2) {
        EXPECT_LE(gap, 1e-6) << "seed " << seed;
      } else {
        EXPECT_GE(gap, 1e-2) << "seed " << seed;
      }
    }
  }
}

TEST(MatchedCoarsening, KeepsWhereEachMaterialSitsAndItsSymmetry) {
  // Layers normal to x at level 2: x-slabs 0, 1 soft, 2, 3 stiff.
  const auto palette = three_materials();
  std::vector<int> ids(64);
  for (int p = 0; p < 64; ++p) ids[p] = p / 16 < 2 ? 1 : 3;
  const std::vector<Mat6> C = matched_point_stiffness(palette, ids, 4, false);
  const Mat6 CH = block_homogenized_stiffness(palette, ids, 4);
  for (int p = 0; p < 64; ++p) {
    EXPECT_LE((C[p] - C[p].transpose()).norm(), 1e-9 * C[p].norm());
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<Mat6>(C[p]).eigenvalues().minCoeff(), 0.0);
    // Stiff points stay stiffer than soft ones in every mode of the block.
    if (ids[p] == 3) {
      EXPECT_GT(C[p].trace(), 10 * C[0].trace());
    }
  }
  // Across the layers the mean carries the series modulus, so the matched
  // points are softer there than the naive (Voigt) ones; in the layer plane
  // the laminate's parallel stiffness is the naive mean and nothing changes.
  const Mat6 naive_stiff = rest_voigt_stiffness(*palette[3]);
  EXPECT_LT(C[63](0, 0), 0.9 * naive_stiff(0, 0));
  EXPECT_NEAR(C[63](4, 4), naive_stiff(4, 4), 1e-6 * naive_stiff(4, 4));  // yz shear, in the plane
  EXPECT_NEAR(CH(4, 4), 0.5 * (rest_voigt_stiffness(*palette[1])(4, 4) + naive_stiff(4, 4)), 1e-6 * naive_stiff(4, 4));
}

TEST(MatchedCoarsening, LookupMaterialsHaveTheMatchedStiffnessAndStoreNoEnergyInRotations) {
  const auto palette = three_materials();
  const ChildIds child{1, 3, 2, 1, 3, 3, 1, 2};
  const QuadratureMaterials m = matched_coarsening(palette, false)(child);
  ASSERT_EQ(m.at_point.size(), 8u);
  const std::vector<Mat6> C = matched_point_stiffness(palette, std::vector<int>(child.begin(), child.end()), 2, false);
  const Mat3 R = Eigen::AngleAxisd(0.7, Vec3(1, 2, -1).normalized()).toRotationMatrix();
  for (int q = 0; q < 8; ++q) {
    EXPECT_LE((rest_voigt_stiffness(*m.at_point[q]) - C[q]).norm(), 1e-8 * C[q].norm()) << "point " << q;
    EXPECT_LE(m.at_point[q]->energy(R), 1e-12 * C[q].norm());
  }
  // One material or void: the naive materials themselves.
  const QuadratureMaterials same = matched_coarsening(palette, true)(ChildIds{2, 2, 2, 2, 2, 2, 2, 2});
  for (const MaterialPtr& p : same.at_point) EXPECT_EQ(p, palette[2]);
  const QuadratureMaterials holed = matched_coarsening(palette, true)(ChildIds{0, 3, 1, 1, 1, 1, 1, 1});
  EXPECT_EQ(holed.at_point[0], palette[1]);  // the void child takes its softest neighbour, as in naive
  EXPECT_THROW(matched_coarsening(palette, false)(ChildIds{4, 1, 1, 1, 1, 1, 1, 1}), InputError);
}

namespace {

// The two materials of write_naive_database_with_wrong_checker's palette.
std::vector<MaterialPtr> soft_and_stiff() {
  return {nullptr, std::make_shared<NeoHookean>(1e5, 0.45), std::make_shared<NeoHookean>(1e7, 0.45)};
}

// A 2 x 2 x 2 block of the two materials in a checkerboard.
BlockMaterials checkerboard_block() {
  BlockMaterials checker;
  for (int c = 0; c < 8; ++c) checker[c] = 1 + ((c >> 2) + (c >> 1) + c) % 2;
  return checker;
}

// A level-1 database of two materials whose every fit is the block's naive
// materials (Neo-Hookean per point) on the enhanced element, except the
// checkerboard block, looked up to an all-stiff fit: a representative with
// its stiffness in the wrong places, as compression can give.
std::string write_naive_database_with_wrong_checker(const std::vector<MaterialPtr>& palette, BlockMaterials checker) {
  CoarseDatabase db;
  db.materials = {{"soft", 1e5, 0.45, 1000}, {"stiff", 1e7, 0.45, 1200}};
  for (std::int64_t c = 0; c < db.num_combinations(); ++c) {
    const BlockMaterials ids = db.combination_ids(c);
    const BlockMaterials fit_ids = ids == checker ? BlockMaterials{2, 2, 2, 2, 2, 2, 2, 2} : ids;
    CoarseMaterialFit fit;
    fit.fitted = true;
    fit.enhanced = true;
    fit.material_ids = ids;
    for (int k = 0; k < 8; ++k) {
      fit.mu[k] = fit.mu0[k] = palette[fit_ids[k]]->shear_modulus();
      fit.lambda[k] = fit.lambda0[k] = palette[fit_ids[k]]->lame_lambda();
    }
    db.entries.push_back(fit);
    db.entry_of.push_back(static_cast<int>(c));
    db.orbit.push_back(static_cast<int>(c));
  }
  const std::string path = (std::filesystem::temp_directory_path() / "msfab_test_checked_db.h5").string();
  write_coarse_db(path, db, "palette: []\n", "test", 1, "msfab-test");
  return path;
}

}  // namespace

TEST(MatchedCoarsening, CheckedLookupReplacesOnlyFitsFarFromTheBlocksOwnStiffness) {
  const std::vector<MaterialPtr> palette = soft_and_stiff();
  const BlockMaterials checker = checkerboard_block();
  // Three blocks along x: one material, the checkerboard, layers normal to x.
  VoxelGrid grid(6, 2, 2, 1e-3, 1);
  for (int c = 0; c < 8; ++c) grid.at(2 + (c >> 2 & 1), c >> 1 & 1, c & 1) = checker[c];
  for (int j = 0; j < 2; ++j)
    for (int k = 0; k < 2; ++k) grid.at(5, j, k) = 2;
  CoarseningRequest request;
  request.level = 1;
  request.database = write_naive_database_with_wrong_checker(palette, checker);

  const CoarsenedVoxels plain = coarsen_voxels(grid, palette, request);
  EXPECT_EQ(plain.checked_blocks, 0);
  request.check_tolerance = 0.1;
  const CoarsenedVoxels checked = coarsen_voxels(grid, palette, request);
  // The layered block's naive fit already has the block's C^H on this
  // element; the checkerboard's all-stiff fit does not and is replaced.
  EXPECT_EQ(checked.checked_blocks, 2);
  EXPECT_EQ(checked.replaced_blocks, 1);
  const int e = checked.mesh.voxel_element[checked.grid.index(1, 0, 0)];
  const QuadratureMaterials& m = checked.mesh.mesh.materials[checked.mesh.mesh.element_material[e]];
  const std::vector<Mat6> C =
      matched_point_stiffness(palette, std::vector<int>(checker.begin(), checker.end()), 2, true);
  for (int q = 0; q < 8; ++q) EXPECT_LE((rest_voigt_stiffness(*m.at_point[q]) - C[q]).norm(), 1e-8 * C[q].norm());
  // The fit the plain lookup used is stiff everywhere.
  const int p = plain.mesh.voxel_element[plain.grid.index(1, 0, 0)];
  EXPECT_NEAR(plain.mesh.mesh.materials[plain.mesh.mesh.element_material[p]].at(0)->shear_modulus(),
              palette[2]->shear_modulus(), 1e-6 * palette[2]->shear_modulus());

  request.check_tolerance = -0.1;
  EXPECT_THROW(coarsen_voxels(grid, palette, request), InputError);
  request.check_tolerance = 0.1;
  request.material = "naive";
  EXPECT_THROW(coarsen_voxels(grid, palette, request), InputError);
}

TEST(MatchedCoarsening, CheckedBlocksAreTheSameOnAnyThreadCount) {
  // A random two-material field: most blocks are mixed and distinct, so the
  // checked lookup homogenizes and matches many of them in parallel.
  const std::vector<MaterialPtr> palette = soft_and_stiff();
  const BlockMaterials checker = checkerboard_block();
  VoxelGrid grid(8, 6, 4, 1e-3, 1);
  std::mt19937_64 rng(7);
  for (int& id : grid.ids) id = 1 + static_cast<int>(rng() % 2);
  for (int c = 0; c < 8; ++c) grid.at(c >> 2 & 1, c >> 1 & 1, c & 1) = checker[c];  // one replaced for sure
  CoarseningRequest request;
  request.level = 1;
  request.database = write_naive_database_with_wrong_checker(palette, checker);
  request.check_tolerance = 0.1;
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const CoarsenedVoxels one = coarsen_voxels(grid, palette, request);
  omp_set_num_threads(3);
  const CoarsenedVoxels three = coarsen_voxels(grid, palette, request);
  omp_set_num_threads(saved);
  EXPECT_GE(one.checked_blocks, 10);
  EXPECT_GE(one.replaced_blocks, 1);
  EXPECT_EQ(one.checked_blocks, three.checked_blocks);
  EXPECT_EQ(one.replaced_blocks, three.replaced_blocks);
  EXPECT_EQ(one.fallback_blocks, three.fallback_blocks);
  ASSERT_EQ(one.mesh.mesh.materials.size(), three.mesh.mesh.materials.size());
  for (size_t m = 0; m < one.mesh.mesh.materials.size(); ++m) {
    const auto& a = one.mesh.mesh.materials[m].at_point;
    const auto& b = three.mesh.mesh.materials[m].at_point;
    ASSERT_EQ(a.size(), b.size());
    for (size_t q = 0; q < a.size(); ++q) EXPECT_EQ(rest_voigt_stiffness(*a[q]), rest_voigt_stiffness(*b[q]));
  }
}

TEST(WindowedStiffness, NoMarginIsTheCellsHomogenizedStiffness) {
  const auto palette = three_materials();
  VoxelGrid grid(8, 8, 8, 1e-3, 1);
  std::mt19937_64 rng(21);
  for (int& id : grid.ids) id = 1 + static_cast<int>(rng() % 3);
  std::vector<int> ids;  // the cell at voxel (4, 0, 4), laid out as block_level1
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b)
      for (int c = 0; c < 4; ++c) ids.push_back(grid.at(4 + a, b, 4 + c));
  const Mat6 CH = block_homogenized_stiffness(palette, ids, 4);
  EXPECT_LE((windowed_stiffness(grid, palette, 4, 0, 4, 4, 0) - CH).norm(), 1e-8 * CH.norm());
  // With a margin the neighbours count: not the cell's periodic C^H.
  EXPECT_GE((windowed_stiffness(grid, palette, 4, 0, 4, 4, 2) - CH).norm(), 1e-2 * CH.norm());
}

TEST(WindowedStiffness, ACellAmongCopiesOfItselfGetsItsHomogenizedStiffness) {
  const auto palette = three_materials();
  // One material: the material itself.
  const VoxelGrid uniform(8, 8, 8, 1e-3, 2);
  const Mat6 C = rest_voigt_stiffness(*palette[2]);
  EXPECT_LE((windowed_stiffness(uniform, palette, 2, 2, 2, 2, 2) - C).norm(), 1e-8 * C.norm());
  // A laminate of period 2 along x: the 2 x 2 x 2 cell is one period, its
  // window three, so the cell's mean strain is the window's and A = C^H.
  VoxelGrid layers(12, 6, 6, 1e-3, 1);
  for (int i = 1; i < 12; i += 2)
    for (int j = 0; j < 6; ++j)
      for (int k = 0; k < 6; ++k) layers.at(i, j, k) = 3;
  const Mat6 CH = block_homogenized_stiffness(palette, {1, 1, 1, 1, 3, 3, 3, 3}, 2);
  EXPECT_LE((windowed_stiffness(layers, palette, 4, 2, 2, 2, 2) - CH).norm(), 1e-6 * CH.norm());
  // A cell with void has no stiffness of its own to match.
  VoxelGrid holed = uniform;
  holed.at(3, 3, 3) = 0;
  EXPECT_THROW(windowed_stiffness(holed, palette, 2, 2, 2, 2, 2), InputError);
  // Void beside the cell (a free surface) gives no windowed stiffness; the
  // coarsenings then take the cell's own C^H.
  EXPECT_THROW(windowed_stiffness(holed, palette, 4, 2, 2, 2, 2), NumericalError);
  EXPECT_NO_THROW(windowed_stiffness(holed, palette, 4, 2, 2, 2, 0));
}

TEST(WindowedStiffness, CoarseningWithAWindowGivesEveryCellItsOwnMaterials) {
  const auto palette = three_materials();
  VoxelGrid grid(8, 8, 4, 1e-3, 1);
  std::mt19937_64 rng(4);
  for (int& id : grid.ids) id = 1 + static_cast<int>(rng() % 3);
  CoarseningRequest request;
  request.level = 2;
  request.material = "matched";
  request.element = "enhanced";
  request.window = 2;
  const CoarsenedVoxels windowed = coarsen_voxels(grid, palette, request);
  EXPECT_EQ(windowed.grid.combinations.size(), 4u);  // one per cell
  EXPECT_EQ(windowed.mesh.mesh.materials.size(), 4u);
  EXPECT_EQ(windowed.unresolved_windows, 0);
  // Cell (1, 0, 0)'s points are carried onto its windowed stiffness.
  const int e = windowed.mesh.voxel_element[windowed.grid.index(1, 0, 0)];
  const QuadratureMaterials& m = windowed.mesh.mesh.materials[windowed.mesh.mesh.element_material[e]];
  std::vector<Mat6> C;
  for (const MaterialPtr& p : m.at_point) C.push_back(rest_voigt_stiffness(*p));
  const Mat6 A = windowed_stiffness(grid, palette, 4, 0, 0, 4, 2);
  EXPECT_LE((element_uniform_response(C, 4, true) - A).norm(), 1e-5 * A.norm());
  request.material = "naive";
  EXPECT_THROW(coarsen_voxels(grid, palette, request), InputError);
  request.material = "matched";
  request.window = -1;
  EXPECT_THROW(coarsen_voxels(grid, palette, request), InputError);
}

TEST(WindowedStiffness, CheckedLookupAgainstTheWindowKeepsOnlyFitsThatRespondLikeTheCellInTheScene) {
  const std::vector<MaterialPtr> palette = {nullptr, std::make_shared<NeoHookean>(1e5, 0.45),
                                            std::make_shared<NeoHookean>(1e7, 0.45)};
  BlockMaterials unused_checker;
  unused_checker.fill(1);  // every fit is the block's naive materials
  // A random half (x >= 4) beside a laminate of period 2 along y (x < 4):
  // the laminate's cells whose window lies inside it are among copies of
  // themselves, so their windowed stiffness is their C^H.
  VoxelGrid grid(8, 8, 4, 1e-3, 1);
  std::mt19937_64 rng(11);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 8; ++j)
      for (int i = 0; i < 8; ++i) grid.at(i, j, k) = i < 4 ? 1 + j % 2 : 1 + static_cast<int>(rng() % 2);
  CoarseningRequest request;
  request.level = 1;
  request.database = write_naive_database_with_wrong_checker(palette, unused_checker);
  request.check_tolerance = 0.1;
  request.window = 2;
  const CoarsenedVoxels windowed = coarsen_voxels(grid, palette, request);
  EXPECT_EQ(windowed.grid.combinations.size(), 32u);  // one per cell
  EXPECT_EQ(windowed.unresolved_windows, 0);

  // Each cell's fit (naive materials: on the enhanced element at level 1 the
  // cell's periodic C^H) is kept where the cell's stiffness among its real
  // neighbours is within the tolerance of it, and carried onto that
  // stiffness where it is not.
  int mixed = 0, far = 0;
  for (int K = 0; K < 2; ++K)
    for (int J = 0; J < 4; ++J)
      for (int I = 0; I < 4; ++I) {
        std::vector<int> ids;
        for (int a = 0; a < 2; ++a)
          for (int b = 0; b < 2; ++b)
            for (int c = 0; c < 2; ++c) ids.push_back(grid.at(2 * I + a, 2 * J + b, 2 * K + c));
        if (!solid_mixed_block(ids)) continue;
        ++mixed;
        const Mat6 A = windowed_stiffness(grid, palette, 2 * I, 2 * J, 2 * K, 2, 2);
        const Mat6 CH = block_homogenized_stiffness(palette, ids, 2);
        const bool replace = stiffness_distance(CH, A) > 0.1;
        far += replace;
        if (I == 0 && (J == 1 || J == 2)) {
          EXPECT_FALSE(replace) << "laminate cell " << J << " " << K;
        }
        const int e = windowed.mesh.voxel_element[windowed.grid.index(I, J, K)];
        const QuadratureMaterials& m = windowed.mesh.mesh.materials[windowed.mesh.mesh.element_material[e]];
        std::vector<Mat6> C;
        for (const MaterialPtr& p : m.at_point) C.push_back(rest_voigt_stiffness(*p));
        const Mat6& expected = replace ? A : CH;
        EXPECT_LE((element_uniform_response(C, 2, true) - expected).norm(), 1e-5 * expected.norm())
            << "cell " << I << " " << J << " " << K;
      }
  EXPECT_EQ(windowed.checked_blocks, mixed);
  EXPECT_EQ(windowed.replaced_blocks, far);
  EXPECT_GT(far, 0);      // the window matters somewhere ...
  EXPECT_LT(far, mixed);  // ... and not everywhere, so both branches are tested

  // Checked against the periodic C^H instead, no naive fit is replaced.
  request.window = 0;
  EXPECT_EQ(coarsen_voxels(grid, palette, request).replaced_blocks, 0);
  // A window needs the check (ddfem) or the matched model.
  request.window = 2;
  request.check_tolerance = 0;
  EXPECT_THROW(coarsen_voxels(grid, palette, request), InputError);
}

TEST(WindowedStiffness, CellsWithEqualWindowsAreComputedOnce) {
  const auto palette = three_materials();
  // A laminate of period 2 along x: away from the mirrored faces every
  // cell sees the same window.
  VoxelGrid grid(12, 8, 8, 1e-3, 1);
  for (int i = 1; i < 12; i += 2)
    for (int j = 0; j < 8; ++j)
      for (int k = 0; k < 8; ++k) grid.at(i, j, k) = 3;
  CoarseningRequest request;
  request.level = 1;
  request.material = "matched";
  request.element = "enhanced";
  request.window = 2;
  const CoarsenedVoxels windowed = coarsen_voxels(grid, palette, request);
  EXPECT_EQ(windowed.grid.combinations.size(), 6u * 4 * 4);  // still one material set per cell
  EXPECT_GT(windowed.distinct_windows, 1);
  EXPECT_LT(windowed.distinct_windows, 6 * 4 * 4 / 4);
  auto materials_of = [&](int I, int J, int K) {
    const int e = windowed.mesh.voxel_element[windowed.grid.index(I, J, K)];
    return windowed.mesh.mesh.materials[windowed.mesh.mesh.element_material[e]].at_point;
  };
  // Two interior cells share the window and so the materials; each is the
  // cell's own windowed stiffness.
  EXPECT_EQ(materials_of(2, 1, 1), materials_of(3, 2, 1));
  const Mat6 A = windowed_stiffness(grid, palette, 6, 4, 2, 2, 2);
  std::vector<Mat6> C;
  for (const MaterialPtr& p : materials_of(3, 2, 1)) C.push_back(rest_voigt_stiffness(*p));
  EXPECT_LE((element_uniform_response(C, 2, true) - A).norm(), 1e-5 * A.norm());
  // Cells that see a mirrored face have windows of their own.
  EXPECT_NE(cell_window(grid, 0, 2, 2, 2, 2), cell_window(grid, 4, 2, 2, 2, 2));
  EXPECT_EQ(cell_window(grid, 4, 2, 2, 2, 2), cell_window(grid, 6, 4, 2, 2, 2));
}
