// DDFEM database pieces: cube symmetries and orbit mapping of fits, the
// combination code, and the coarse_db artifact round trip.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>
#include <set>

#include "core/errors.hpp"
#include "ddfem/coarse_db.hpp"
#include "ddfem/cube_symmetry.hpp"
#include "ddfem/db_compression.hpp"
#include "ddfem/fine_block.hpp"
#include "material/neo_hookean.hpp"

namespace msfab {
namespace {

CoarseMaterialFit random_fit(std::mt19937_64& rng, const BlockMaterials& ids) {
  auto u01 = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  CoarseMaterialFit f;
  f.fitted = true;
  f.material_ids = ids;
  for (int k = 0; k < 8; ++k) {
    f.mu[k] = 1e5 * (0.5 + u01());
    f.lambda[k] = 4e5 * (0.5 + u01());
    f.C[k] = 2e5 * u01();
    f.v[k] = Vec3(u01() - 0.5, u01() - 0.5, u01() - 0.5).normalized();
  }
  f.lambda_centre = u01() < 0.5 ? 0.0 : 3e5 * u01();
  f.heldout_error = u01();
  return f;
}

TEST(DdfemSymmetry, FortyEightDistinctSymmetriesActingOnChildren) {
  const auto& all = cube_symmetries();
  ASSERT_EQ(all.size(), 48u);
  EXPECT_TRUE(all[0].matrix.isIdentity());
  std::set<std::array<int, 8>> perms;
  for (const CubeSymmetry& S : all) {
    EXPECT_NEAR(std::abs(S.matrix.determinant()), 1.0, 1e-15);
    perms.insert(S.child);
  }
  EXPECT_EQ(perms.size(), 48u);
  // Orbits of 2-colourings of the cube's corners: 22 (Burnside).
  std::set<BlockMaterials> reps;
  for (int code = 0; code < 256; ++code) {
    BlockMaterials ids;
    for (int c = 0; c < 8; ++c) ids[c] = 1 + (code >> c & 1);
    const CanonicalBlock canon = canonical_block(ids);
    EXPECT_EQ(apply_symmetry(all[canon.symmetry], ids), canon.ids);
    reps.insert(canon.ids);
  }
  EXPECT_EQ(reps.size(), 22u);
}

TEST(DdfemSymmetry, MappedFitGivesTheSameEnergyForTheMirroredDeformation) {
  std::mt19937_64 rng(4);
  auto u01 = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  const auto pal = std::vector<MaterialPtr>{nullptr, std::make_shared<NeoHookean>(1e6, 0.3)};
  const FineBlock block = make_fine_block(BlockMaterials{1, 1, 1, 1, 1, 1, 1, 1}, pal, 1e-3);
  const hex8::ElementGeometry geo = block.coarse_geometry();
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  const BlockMaterials ids{1, 2, 2, 1, 3, 1, 2, 3};
  for (const CubeSymmetry& S : cube_symmetries()) {
    const BlockMaterials image_ids = apply_symmetry(S, ids);
    const CoarseMaterialFit image = random_fit(rng, image_ids);
    const CoarseMaterialFit fit = map_fit_back(S, image, ids);
    EXPECT_EQ(fit.material_ids, ids);
    Vec24 u, u_image;
    for (int i = 0; i < 24; ++i) u[i] = 1e-4 * (2 * u01() - 1);
    // The mirrored configuration: corner S.child[c] moves by S u_c.
    for (int c = 0; c < 8; ++c) u_image.segment<3>(3 * S.child[c]) = S.matrix * u.segment<3>(3 * c);
    const double E = coarse_energy(fit, geo, X, u), E_image = coarse_energy(image, geo, X, u_image);
    ASSERT_GT(E, 0);
    EXPECT_NEAR(E, E_image, 1e-12 * E);
  }
}

TEST(DdfemDatabase, CombinationCodesRoundTripAndArtifactReadsBack) {
  CoarseDatabase db;
  db.materials = {{"soft", 1e5, 0.45, 1000}, {"stiff", 1e7, 0.45, 1200}};
  ASSERT_EQ(db.num_combinations(), 256);
  std::mt19937_64 rng(8);
  for (std::int64_t c = 0; c < db.num_combinations(); ++c) {
    const BlockMaterials ids = db.combination_ids(c);
    EXPECT_EQ(db.combination_code(ids), c);
    db.entries.push_back(random_fit(rng, ids));
    db.entry_of.push_back(static_cast<int>(c));
    db.orbit.push_back(static_cast<int>(db.combination_code(canonical_block(ids).ids)));
  }
  EXPECT_EQ(db.combination_code(BlockMaterials{1, 0, 1, 1, 1, 1, 1, 1}), -1);
  EXPECT_EQ(db.combination_code(BlockMaterials{1, 3, 1, 1, 1, 1, 1, 1}), -1);
  const std::string path = (std::filesystem::temp_directory_path() / "msfab_test_db.h5").string();
  write_coarse_db(path, db, "palette: []\n", "test", 1, "msfab-test");
  const CoarseDatabase back = read_coarse_db(path);
  ASSERT_EQ(back.entries.size(), db.entries.size());
  for (std::size_t e = 0; e < db.entries.size(); ++e) {
    EXPECT_EQ(back.entries[e].mu, db.entries[e].mu);
    EXPECT_EQ(back.entries[e].C, db.entries[e].C);
    EXPECT_EQ(back.entries[e].lambda_centre, db.entries[e].lambda_centre);
    for (int k = 0; k < 8; ++k) EXPECT_EQ(back.entries[e].v[k], db.entries[e].v[k]);
    EXPECT_EQ(back.orbit[e], db.orbit[e]);
  }
  EXPECT_EQ(back.find(BlockMaterials{1, 2, 1, 1, 1, 1, 1, 1}), &back.entries[2]);
  EXPECT_EQ(back.find(BlockMaterials{0, 2, 1, 1, 1, 1, 1, 1}), nullptr);
  EXPECT_FALSE(back.enhanced_element());

  // The element the fits are for reads back; fits for two elements in one
  // database are refused.
  for (CoarseMaterialFit& fit : db.entries) fit.enhanced = true;
  write_coarse_db(path, db, "palette: []\n", "test", 1, "msfab-test");
  EXPECT_TRUE(read_coarse_db(path).enhanced_element());
  for (const CoarseMaterialFit& fit : read_coarse_db(path).entries) EXPECT_TRUE(fit.enhanced);
  db.entries[3].enhanced = false;
  EXPECT_THROW(write_coarse_db(path, db, "palette: []\n", "test", 1, "msfab-test"), std::invalid_argument);
  db.entries[3].enhanced = true;

  // Palette checks against a scene.
  const std::vector<MaterialPtr> scene = {nullptr, std::make_shared<NeoHookean>(1e5, 0.45),
                                          std::make_shared<NeoHookean>(1e7, 0.40)};
  EXPECT_NO_THROW(check_scene_palette(back, path, scene, {0, 1}));
  EXPECT_THROW(check_scene_palette(back, path, scene, {1, 2}), InputError);
  const std::vector<MaterialPtr> three = {nullptr, scene[1], std::make_shared<NeoHookean>(1e7, 0.45), scene[1]};
  EXPECT_THROW(check_scene_palette(back, path, three, {1, 3}), InputError);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace msfab

namespace msfab {
namespace {

TEST(DdfemCompression, FarthestPointSetMatchesBruteForceAndRepresentativesMapToThemselves) {
  // Points on a line: from 0 the farthest is 10, then 4 (distance 4 to 0,
  // 6 to 10), then 7 (3 to 4, 3 to 10: tie broken by the lower row).
  MatX f(6, 1);
  f << 0.0, 1.0, 4.0, 7.0, 9.5, 10.0;
  const FarthestPointSet s = farthest_point_sampling(f, 4, 0);
  EXPECT_EQ(s.representatives, (std::vector<int>{0, 5, 2, 3}));
  for (std::size_t r = 0; r < s.representatives.size(); ++r) {
    EXPECT_EQ(s.nearest[s.representatives[r]], int(r));
    EXPECT_EQ(s.distance[s.representatives[r]], 0.0);
  }
  EXPECT_EQ(s.nearest[1], 0);  // 1 is closest to 0
  EXPECT_EQ(s.nearest[4], 1);  // 9.5 to 10

  // Random 3-D points against a direct implementation of the definition.
  std::mt19937_64 rng(12);
  MatX g(40, 3);
  for (int i = 0; i < g.size(); ++i) g.data()[i] = double(rng() >> 11) * 0x1.0p-53;
  const FarthestPointSet t = farthest_point_sampling(g, 7, 5);
  std::vector<int> chosen{5};
  while (chosen.size() < 7) {
    int best = -1;
    double best_d = -1;
    for (int i = 0; i < g.rows(); ++i) {
      double d = 1e300;
      for (int c : chosen) d = std::min(d, (g.row(i) - g.row(c)).norm());
      if (d > best_d) best_d = d, best = i;
    }
    chosen.push_back(best);
  }
  EXPECT_EQ(t.representatives, chosen);
  EXPECT_THROW(farthest_point_sampling(g, 41, 0), InputError);
}

TEST(DdfemCompression, CompressedDatabaseLooksEveryCombinationUpToARepresentative) {
  CoarseDatabase db;
  db.materials = {{"soft", 1e5, 0.45, 1000}, {"stiff", 1e7, 0.45, 1200}};
  std::mt19937_64 rng(8);
  for (std::int64_t c = 0; c < db.num_combinations(); ++c) {
    CoarseMaterialFit f = random_fit(rng, db.combination_ids(c));
    for (int k = 0; k < 8; ++k) f.C[k] = 0;  // energies stay positive for every deformation
    db.entries.push_back(f);
    db.entry_of.push_back(static_cast<int>(c));
    db.orbit.push_back(static_cast<int>(c));
  }
  CompressionReport report;
  const CoarseDatabase small = compress_database(db, 10, 16, 0.05, 3, &report);
  ASSERT_EQ(small.entries.size(), 10u);
  EXPECT_TRUE(small.compressed());
  for (const CoarseMaterialFit& rep : small.entries) EXPECT_EQ(small.find(rep.material_ids), &rep);
  // Uniform blocks are kept exactly.
  for (int m = 1; m <= 2; ++m) {
    const BlockMaterials uniform{m, m, m, m, m, m, m, m};
    EXPECT_EQ(small.find(uniform)->material_ids, uniform);
  }
  for (std::int64_t c = 0; c < db.num_combinations(); ++c) ASSERT_NE(small.find(db.combination_ids(c)), nullptr);
  EXPECT_GT(report.max_distance, 0);
  EXPECT_THROW(compress_database(small, 5, 16, 0.05, 3), InputError);
  // Same seed, same result.
  const CoarseDatabase again = compress_database(db, 10, 16, 0.05, 3);
  EXPECT_EQ(again.entry_of, small.entry_of);
  // With the corner moves: still every combination has a representative,
  // each representative is its own, uniform blocks are exact.
  const CoarseDatabase corners = compress_database(db, 10, 16, 0.05, 3, nullptr, true);
  for (const CoarseMaterialFit& rep : corners.entries) EXPECT_EQ(corners.find(rep.material_ids), &rep);
  for (int m = 1; m <= 2; ++m) {
    const BlockMaterials uniform{m, m, m, m, m, m, m, m};
    EXPECT_EQ(corners.find(uniform)->material_ids, uniform);
  }
  EXPECT_NE(corners.entry_of, small.entry_of);
}

// The single-corner moves: one corner moved by strain x edge along one axis.
TEST(DdfemCompression, CornerMovesMoveOneCornerAlongOneAxis) {
  FineBlock unit;
  unit.voxel_size = 1e-3;
  const std::vector<Vec24> moves = corner_deformations(unit.coarse_rest_positions(), 0.05);
  ASSERT_EQ(moves.size(), 24u);
  for (int i = 0; i < 24; ++i) {
    EXPECT_DOUBLE_EQ(moves[i][i], 0.05 * 2e-3) << i;
    EXPECT_DOUBLE_EQ(moves[i].norm(), 0.05 * 2e-3) << i;
  }
  EXPECT_THROW(corner_deformations(unit.coarse_rest_positions(), 0.0), InputError);
}

}  // namespace
}  // namespace msfab
