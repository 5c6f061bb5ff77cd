// DDFEM level 2 (thesis §2.3.5): the 2x1x1 -> 1x2x1 -> 1x1x2 hierarchy of
// pair databases, its features and lookups, and the level-2 artifact.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "core/errors.hpp"
#include "ddfem/coarse_db.hpp"
#include "ddfem/db_compression.hpp"
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

// Entry i is labelled as a block of palette material i + 1 where `uniform`
// holds it, else as a mixed block.
std::vector<CoarseMaterialFit> random_palette(int n, std::uint64_t seed, bool springs = false,
                                              std::vector<int> uniform = {}) {
  std::mt19937_64 rng(seed);
  std::vector<CoarseMaterialFit> out;
  for (int i = 0; i < n; ++i) {
    out.push_back(random_level1(rng, std::pow(10.0, 5 + i % 3), springs));
    out.back().material_ids = BlockMaterials{1, 2, 1, 1, 1, 1, 1, 1};
  }
  for (int i : uniform) out[i].material_ids.fill(i + 1);
  return out;
}

Arrangement arrangement_of_code(int code, int k1) {
  Arrangement e;
  for (int c = 0; c < 8; ++c) e[c] = code % k1, code /= k1;
  return e;
}

// Quadratic energy of the assembled block with its 8 corners displaced by
// u and the other nodes relaxed, solved independently of the condensation:
// the sparse Hessian of the assembled mesh, a dense LU on the free nodes.
double relaxed_block_energy(const FineBlock& block, const Vec24& u) {
  const ElasticAssembler assembler(block.mesh());
  SpMat H = assembler.pattern();
  assembler.evaluate(assembler.rest_positions(), nullptr, &H);
  const MatX K(H);
  const int n = static_cast<int>(K.rows());
  VecX x = VecX::Zero(n);
  std::vector<bool> fixed(n, false);
  for (int c = 0; c < 8; ++c)
    for (int a = 0; a < 3; ++a)
      x[3 * block.corner_nodes[c] + a] = u[3 * c + a], fixed[3 * block.corner_nodes[c] + a] = true;
  std::vector<int> free;
  for (int i = 0; i < n; ++i)
    if (!fixed[i]) free.push_back(i);
  MatX Kff(free.size(), free.size());
  VecX rhs(free.size());
  for (std::size_t i = 0; i < free.size(); ++i) {
    rhs[i] = -(K.row(free[i]) * x)(0);
    for (std::size_t j = 0; j < free.size(); ++j) Kff(i, j) = K(free[i], free[j]);
  }
  const VecX xf = Kff.fullPivLu().solve(rhs);
  for (std::size_t i = 0; i < free.size(); ++i) x[free[i]] = xf[i];
  return 0.5 * x.dot(K * x);
}

TEST(DdfemHierarchy, CondensedStiffnessIsTheRelaxedEnergyOfTheBlock) {
  const auto level1 = random_palette(3, 4, true);
  const std::vector<Mat24> K1 = level1_rest_stiffness(level1, kChild);
  const Arrangement arr{0, 2, 1, 1, 2, 0, 0, 2};
  Eigen::Vector3i extent;
  const Mat24 S = condensed_stiffness(arr, K1, &extent);
  EXPECT_EQ(extent, Eigen::Vector3i(2, 2, 2));
  EXPECT_LT((S - S.transpose()).norm(), 1e-9 * S.norm());
  std::array<const CoarseMaterialFit*, 8> children;
  for (int c = 0; c < 8; ++c) children[c] = &level1[arr[c]];
  const FineBlock block = make_block_of_coarse_materials(children, BlockMaterials{1, 1, 1, 1, 1, 1, 1, 1}, kChild);
  const auto defs = smooth_deformations(2 * kChild, 5, 0.05, 9);
  for (std::size_t d = 0; d < defs.size(); ++d) {
    const Vec24 u = box_corner_displacements(defs[d], extent, kChild);
    const double condensed = 0.5 * u.dot(S * u), reference = relaxed_block_energy(block, u);
    ASSERT_GT(reference, 0);
    EXPECT_NEAR(condensed, reference, 1e-8 * reference) << "deformation " << d;
  }
  // Rigid corner motions store nothing; relaxing never raises the energy
  // above that of a homogeneous block deformed affinely everywhere.
  Vec24 rigid;
  const Vec3 t(1e-4, -2e-4, 3e-4), w(0.01, -0.02, 0.015);
  for (int c = 0; c < 8; ++c) rigid.segment<3>(3 * c) = t + w.cross(2 * kChild * Vec3(c >> 2 & 1, c >> 1 & 1, c & 1));
  EXPECT_LT(0.5 * rigid.dot(S * rigid), 1e-10 * S.norm() * rigid.squaredNorm());
  CoarseMaterialFit nh(8);
  nh.fitted = true;
  for (int k = 0; k < 8; ++k) nh.mu[k] = 3e5, nh.lambda[k] = 7e5;
  const std::vector<Mat24> Kh = level1_rest_stiffness({nh}, kChild);
  const Mat24 Sh = condensed_stiffness(Arrangement{0, 0, 0, 0, 0, 0, 0, 0}, Kh);
  Mat3 G;
  G << 0.01, 0.002, -0.003, 0.001, -0.004, 0.002, 0.0, 0.003, 0.005;
  Vec24 u;
  for (int c = 0; c < 8; ++c) u.segment<3>(3 * c) = G * (2 * kChild * Vec3(c >> 2 & 1, c >> 1 & 1, c & 1));
  double affine = 0;  // all 8 elements under the same affine field
  for (int c = 0; c < 8; ++c) {
    Vec24 ue;
    for (int n = 0; n < 8; ++n)
      ue.segment<3>(3 * n) =
          G * (kChild * Vec3((c >> 2 & 1) + (n >> 2 & 1), (c >> 1 & 1) + (n >> 1 & 1), (c & 1) + (n & 1)));
    affine += 0.5 * ue.dot(Kh[0] * ue);
  }
  const double relaxed = 0.5 * u.dot(Sh * u);
  EXPECT_GT(relaxed, 0.0);
  EXPECT_LT(relaxed, affine);
  // Partial arrangements span their own box.
  condensed_stiffness(Arrangement{1, -1, -1, -1, 2, -1, -1, -1}, K1, &extent);
  EXPECT_EQ(extent, Eigen::Vector3i(2, 1, 1));
  condensed_stiffness(Arrangement{1, -1, 0, -1, 2, -1, 1, -1}, K1, &extent);
  EXPECT_EQ(extent, Eigen::Vector3i(2, 2, 1));
  // Same seed, same deformations; another seed, others.
  EXPECT_EQ(smooth_deformations(2 * kChild, 5, 0.05, 9)[3].B, defs[3].B);
  EXPECT_NE(smooth_deformations(2 * kChild, 5, 0.05, 10)[3].B, defs[3].B);
}

// Two uniform level-1 materials 100x apart (ids 1 and 2).
std::vector<CoarseMaterialFit> soft_and_stiff_level1() {
  std::vector<CoarseMaterialFit> level1(2, CoarseMaterialFit(8));
  for (int m = 0; m < 2; ++m) {
    level1[m].fitted = true;
    level1[m].material_ids.fill(m + 1);
    for (int k = 0; k < 8; ++k) level1[m].mu[k] = m ? 3.4e6 : 3.4e4, level1[m].lambda[k] = m ? 3.1e7 : 3.1e5;
  }
  return level1;
}

TEST(DdfemHierarchy, SoftHalfOfACellIsNotLookedUpToAStiffOne) {
  // Two uniform level-1 materials 100x apart and the cells mixing them:
  // a cell with a soft half along y must find a representative with the
  // same halves, the case that imposing the deformation on every node got
  // wrong (the stiff half's energy hid the soft half).
  const std::vector<CoarseMaterialFit> level1 = soft_and_stiff_level1();
  HierarchyOptions o;
  o.representatives = {4, 16, 24};
  o.deformations = 16;
  const Level2Hierarchy h = build_level2_hierarchy(level1, kChild, o);
  Arrangement bilayer;
  for (int c = 0; c < 8; ++c) bilayer[c] = c >> 1 & 1;  // soft at j = 0, stiff at j = 1
  EXPECT_EQ(h.arrangement(2, h.lookup(bilayer)), bilayer);
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

// With the corner moves among the features every arrangement still finds
// itself in uncompressed stages; and the moves tell apart two cells whose
// stiff child sits at opposite corners, which the smooth deformations,
// seeing the cell as a whole, nearly take for one another.
TEST(DdfemHierarchy, CornerMovesSeeWhereTheStiffChildSits) {
  const std::vector<CoarseMaterialFit> level1 = soft_and_stiff_level1();
  HierarchyOptions o;
  o.representatives = {4, 16, 256};
  o.deformations = 8;
  o.corner_moves = true;
  EXPECT_EQ(o.features(), 32);
  const Level2Hierarchy all = build_level2_hierarchy(level1, kChild, o);
  for (int code = 0; code < 256; ++code) {
    const Arrangement e = arrangement_of_code(code, 2);
    ASSERT_EQ(all.arrangement(2, all.lookup(e)), e) << "arrangement " << code;
  }
  Arrangement at0, at7;
  at0.fill(0), at7.fill(0);
  at0[0] = 1, at7[7] = 1;
  const std::vector<Mat24> K1 = level1_rest_stiffness(level1, kChild);
  const Mat24 S0 = condensed_stiffness(at0, K1), S7 = condensed_stiffness(at7, K1);
  // Moving corner 0 alone meets the stiff child in one cell, soft ones in the other.
  EXPECT_GT(S0(0, 0), 2.5 * S7(0, 0));
  EXPECT_GT(S7(21, 21), 2.5 * S0(21, 21));
  // A smooth deformation of the whole cell stores nearly the same in both.
  const auto defs = smooth_deformations(2 * kChild, 8, 0.05, 5);
  Eigen::Vector3i extent;
  condensed_stiffness(at0, K1, &extent);
  for (const SmoothDeformation& d : defs) {
    const Vec24 u = box_corner_displacements(d, extent, kChild);
    const double e0 = u.dot(S0 * u), e7 = u.dot(S7 * u);
    EXPECT_LT(std::abs(std::log(e0 / e7)), std::log(1.5));
  }
}

TEST(DdfemHierarchy, CompressedLookupIsConsistentAndPicksANearRepresentative) {
  const int k1 = 3;
  const auto level1 = random_palette(k1, 6, false, {0, 2});
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
  // Cells of one homogeneous level-1 material are kept exactly.
  for (int m : {0, 2}) {
    Arrangement uniform;
    uniform.fill(m);
    EXPECT_EQ(h.arrangement(2, h.lookup(uniform)), uniform);
  }

  // Over all 3^8 arrangements, the representative the hierarchy picks is
  // nearer (Eq. 2.10 on the full block's features) than the average one.
  const auto defs = smooth_deformations(2 * kChild, o.deformations, o.strain, o.seed);
  const std::vector<Mat24> K1 = level1_rest_stiffness(level1, kChild);
  auto features = [&](const Arrangement& a) {
    const Mat24 S = condensed_stiffness(a, K1);
    VecX f(o.deformations);
    for (int d = 0; d < o.deformations; ++d) {
      const Vec24 u = box_corner_displacements(defs[d], Eigen::Vector3i(2, 2, 2), kChild);
      f[d] = std::log(0.5 * u.dot(S * u));
    }
    return f;
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
  EXPECT_LT(picked, 0.6 * average);
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
    // Eq. 2.9's p^0: the palette material of the fine voxel under the point.
    int child = 0;
    const int k = level1_point_of(29, &child);
    const int voxel_id = level1->entries[back.hierarchy.arrangement(2, r)[child]].material_ids[k];
    EXPECT_EQ(back.entries[r].mu0[29], back.level1->palette()[voxel_id]->shear_modulus());
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
