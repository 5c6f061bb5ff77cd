// DDFEM level 2 (thesis §2.3.5): the 2x1x1 -> 1x2x1 -> 1x1x2 hierarchy of
// pair databases, its features and lookups, and the level-2 artifact.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "core/errors.hpp"
#include "ddfem/coarse_db.hpp"
#include "ddfem/hierarchy.hpp"
#include "ddfem/level2_block.hpp"
#include "fem/elastic_assembler.hpp"

namespace msfab {
namespace {

constexpr double kChild = 2e-3;  // level-1 element edge

// A fitted level-1 material with random positive parameters at its points.
CoarseMaterialFit random_level1(std::mt19937_64& rng, double scale, bool springs) {
  auto u01 = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  CoarseMaterialFit f(8);
  f.fitted = true;
  f.material_ids.fill(1);
  for (int k = 0; k < 8; ++k) {
    f.mu[k] = scale * (0.5 + u01());
    f.lambda[k] = 4 * scale * (0.5 + u01());
    f.C[k] = springs ? scale * u01() : 0.0;
    f.v[k] = Vec3(u01() - 0.5, u01() - 0.5, u01() - 0.5).normalized();
  }
  return f;
}

std::vector<CoarseMaterialFit> random_palette(int n, std::uint64_t seed, bool springs = false) {
  std::mt19937_64 rng(seed);
  std::vector<CoarseMaterialFit> out;
  for (int i = 0; i < n; ++i) out.push_back(random_level1(rng, std::pow(10.0, 5 + i % 3), springs));
  return out;
}

Arrangement arrangement_of_code(int code, int k1) {
  Arrangement e;
  for (int c = 0; c < 8; ++c) e[c] = code % k1, code /= k1;
  return e;
}

TEST(DdfemHierarchy, FeaturesAreTheEnergyOfTheBlockOfLevel1Elements) {
  // The stage features add the children's energies; that must be the energy
  // of the assembled 2 x 2 x 2 mesh of level-1 elements under the same field.
  const auto level1 = random_palette(3, 4, true);
  const auto defs = smooth_deformations(2 * kChild, 5, 0.05, 9);
  const auto E = child_energies(level1, kChild, defs);
  const Arrangement arr{0, 2, 1, 1, 2, 0, 0, 2};
  std::array<const CoarseMaterialFit*, 8> children;
  for (int c = 0; c < 8; ++c) children[c] = &level1[arr[c]];
  const FineBlock block = make_block_of_coarse_materials(children, BlockMaterials{1, 1, 1, 1, 1, 1, 1, 1}, kChild);
  const ElasticAssembler assembler(block.mesh());
  const VecX X = assembler.rest_positions();
  for (std::size_t d = 0; d < defs.size(); ++d) {
    VecX x = X;
    for (int n = 0; n < X.size() / 3; ++n) x.segment<3>(3 * n) += defs[d].at(X.segment<3>(3 * n));
    double sum = 0;
    for (int c = 0; c < 8; ++c) sum += E[arr[c]][c][d];
    EXPECT_NEAR(sum, assembler.energy(x), 1e-10 * sum) << "deformation " << d;
  }
  // Same seed, same deformations; another seed, others.
  EXPECT_EQ(smooth_deformations(2 * kChild, 5, 0.05, 9)[3].B, defs[3].B);
  EXPECT_NE(smooth_deformations(2 * kChild, 5, 0.05, 10)[3].B, defs[3].B);
}

TEST(DdfemHierarchy, UncompressedStagesLookEveryArrangementUpToItself) {
  const auto level1 = random_palette(2, 5);
  HierarchyOptions o;
  o.representatives = {4, 16, 256};
  o.deformations = 8;
  const Level2Hierarchy h = build_level2_hierarchy(level1, kChild, o);
  ASSERT_EQ(h.num_final(), 256);
  for (int s = 0; s < 3; ++s) EXPECT_EQ(h.stages[s].max_distance, 0.0);
  for (int code = 0; code < 256; ++code) {
    const Arrangement e = arrangement_of_code(code, 2);
    ASSERT_EQ(h.arrangement(2, h.lookup(e)), e) << "arrangement " << code;
  }
}

TEST(DdfemHierarchy, CompressedLookupIsConsistentAndPicksANearRepresentative) {
  const int k1 = 3;
  const auto level1 = random_palette(k1, 6);
  HierarchyOptions o;
  o.representatives = {5, 10, 20};
  o.deformations = 12;
  const Level2Hierarchy h = build_level2_hierarchy(level1, kChild, o);
  ASSERT_EQ(h.num_final(), 20);
  EXPECT_EQ(h.level1_entries(), k1);
  // A final representative's own arrangement is looked up to itself: the
  // lookup composes the stages exactly as arrangement() decomposes them.
  for (int r = 0; r < h.num_final(); ++r) EXPECT_EQ(h.lookup(h.arrangement(2, r)), r);
  for (int s = 0; s < 3; ++s) EXPECT_GT(h.stages[s].max_distance, 0.0);

  // Over all 3^8 arrangements, the representative the hierarchy picks is
  // nearer (Eq. 2.10 on the full block's features) than the average one.
  const auto defs = smooth_deformations(2 * kChild, o.deformations, o.strain, o.seed);
  const auto E = child_energies(level1, kChild, defs);
  auto features = [&](const Arrangement& a) {
    VecX f = VecX::Zero(o.deformations);
    for (int c = 0; c < 8; ++c)
      for (int d = 0; d < o.deformations; ++d) f[d] += E[a[c]][c][d];
    return VecX(f.array().log());
  };
  std::vector<VecX> reps;
  for (int r = 0; r < h.num_final(); ++r) reps.push_back(features(h.arrangement(2, r)));
  double picked = 0, average = 0;
  int n = 0;
  for (int code = 0; code < 6561; code += 7, ++n) {
    const Arrangement e = arrangement_of_code(code, k1);
    const VecX f = features(e);
    picked += (f - reps[h.lookup(e)]).norm();
    for (const VecX& r : reps) average += (f - r).norm() / reps.size();
  }
  std::printf("[hierarchy] mean distance to the looked-up representative %.3f, to an average one %.3f\n", picked / n,
              average / n);
  EXPECT_LT(picked, 0.5 * average);
  EXPECT_THROW(h.lookup(Arrangement{0, 0, 0, 3, 0, 0, 0, 0}), std::out_of_range);
}

TEST(DdfemHierarchy, Level2DatabaseRoundTripAndLookup) {
  auto level1 = std::make_shared<CoarseDatabase>();
  level1->materials = {{"soft", 1e5, 0.45, 1000}, {"stiff", 1e7, 0.45, 1200}};
  const auto fits = random_palette(4, 7);
  for (std::int64_t c = 0; c < level1->num_combinations(); ++c) {
    level1->entry_of.push_back(static_cast<int>(c % 4));  // a database compressed to 4 materials
    level1->orbit.push_back(static_cast<int>(c));
  }
  level1->entries = fits;
  for (int e = 0; e < 4; ++e) level1->entries[e].material_ids = level1->combination_ids(e);
  level1->num_orbits = 256;

  CoarseDatabase db;
  db.level = 2;
  db.materials = level1->materials;
  db.level1 = level1;
  HierarchyOptions o;
  o.representatives = {6, 9, 7};
  o.deformations = 6;
  db.hierarchy = build_level2_hierarchy(level1->entries, kChild, o);
  std::mt19937_64 rng(12);
  for (int r = 0; r < db.hierarchy.num_final(); ++r) {
    CoarseMaterialFit f(64);
    f.fitted = true;
    const Arrangement arr = db.hierarchy.arrangement(2, r);
    for (int c = 0; c < 8; ++c) f.material_ids[c] = arr[c] + 1;
    for (int q = 0; q < 64; ++q) {
      f.mu[q] = 1e5 * (1 + double(rng() % 100));
      f.lambda[q] = 2 * f.mu[q];
      f.C[q] = 1e3 * double(rng() % 7);
      f.v[q] = Vec3(1, double(rng() % 3), 2).normalized();
    }
    db.entries.push_back(f);
  }
  const std::string path = (std::filesystem::temp_directory_path() / "msfab_test_db_level2.h5").string();
  write_coarse_db(path, db, "level2: {}\n", "test", 1, "msfab-test");
  const CoarseDatabase back = read_coarse_db(path);
  std::filesystem::remove(path);
  ASSERT_EQ(back.level, 2);
  ASSERT_TRUE(back.level1);
  EXPECT_EQ(back.level1->entry_of, level1->entry_of);
  ASSERT_EQ(back.entries.size(), db.entries.size());
  for (std::size_t r = 0; r < db.entries.size(); ++r) {
    EXPECT_EQ(back.entries[r].points(), 64);
    EXPECT_EQ(back.entries[r].mu, db.entries[r].mu);
    EXPECT_EQ(back.entries[r].C, db.entries[r].C);
    for (int q = 0; q < 64; ++q) ASSERT_EQ(back.entries[r].v[q], db.entries[r].v[q]);
    // Eq. 2.9's p^0: the level-1 parameters in the same fine voxel.
    int child = 0;
    const int k = level1_point_of(29, &child);
    EXPECT_EQ(back.entries[r].mu0[29], level1->entries[back.hierarchy.arrangement(2, r)[child]].mu[k]);
  }
  for (int s = 0; s < 3; ++s) {
    EXPECT_EQ(back.hierarchy.stages[s].table, db.hierarchy.stages[s].table);
    EXPECT_EQ(back.hierarchy.stages[s].pairs, db.hierarchy.stages[s].pairs);
  }
  const Arrangement e{3, 1, 0, 2, 2, 2, 1, 0};
  EXPECT_EQ(&back.find_level2(e), &back.entries[db.hierarchy.lookup(e)]);
}

TEST(DdfemHierarchy, RejectsUnfittedOrEmptyLevel1Palettes) {
  HierarchyOptions o;
  EXPECT_THROW(build_level2_hierarchy({}, kChild, o), InputError);
  auto level1 = random_palette(2, 3);
  level1[1].fitted = false;
  EXPECT_THROW(build_level2_hierarchy(level1, kChild, o), InputError);
  o.representatives = {4, 0, 4};
  EXPECT_THROW(build_level2_hierarchy(random_palette(2, 3), kChild, o), InputError);
}

}  // namespace
}  // namespace msfab
