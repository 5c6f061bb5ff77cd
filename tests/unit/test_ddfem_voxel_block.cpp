// Level-2 blocks sampled on their fine voxels (make_voxel_block): the
// 4 x 4 x 4 layout, the points' priors, periodic relaxation of a block of
// n^3 voxels and the per-point spring directions.
#include <gtest/gtest.h>

#include <set>

#include "ddfem/level2_block.hpp"
#include "ddfem_test_blocks.hpp"

namespace msfab {
namespace {

using ddfem_test::kVoxel;
using ddfem_test::two_materials;

CoarseMaterialFit level1_with_ids(const BlockMaterials& ids) {
  CoarseMaterialFit fit(8);
  fit.material_ids = ids;
  return fit;
}

// Corner displacements of the affine field u = G X on a block's coarse element.
Vec24 affine_corners(const FineBlock& b, const Mat3& G) {
  const hex8::NodeMatrix X = b.coarse_rest_positions();
  Vec24 u;
  for (int c = 0; c < 8; ++c) u.segment<3>(3 * c) = G * X.row(c).transpose();
  return u;
}

TEST(DdfemVoxelBlock, EachChildsVoxelsFillItsOctant) {
  std::array<CoarseMaterialFit, 8> fits;
  std::array<const CoarseMaterialFit*, 8> children{};
  for (int c = 0; c < 8; ++c) {
    BlockMaterials ids;
    for (int v = 0; v < 8; ++v) ids[v] = 10 * c + v + 1;  // child c, its voxel v
    fits[c] = level1_with_ids(ids);
    children[c] = c == 5 ? nullptr : &fits[c];
  }
  const std::vector<int> voxels = level2_voxel_ids(children);
  ASSERT_EQ(voxels.size(), 64u);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) {
        const int c = 4 * (i / 2) + 2 * (j / 2) + k / 2, v = 4 * (i % 2) + 2 * (j % 2) + k % 2;
        EXPECT_EQ(voxels[i + 4 * (j + 4 * k)], c == 5 ? 0 : 10 * c + v + 1) << i << j << k;
      }
}

TEST(DdfemVoxelBlock, OnePointInEachVoxelWithThatVoxelsMaterial) {
  const auto pal = two_materials(1e5, 1e7);
  std::vector<int> ids(64);
  for (int v = 0; v < 64; ++v) ids[v] = (v % 3 == 0) ? 0 : 1 + (v % 5 == 0);
  const FineBlock b = make_voxel_block(ids, pal, kVoxel, BlockMaterials{1, 2, 3, 4, 5, 6, 7, 8});
  EXPECT_EQ(b.coarse_points(), 64);
  EXPECT_DOUBLE_EQ(b.edge(), 4 * kVoxel);
  const hex8::ElementGeometry geo = b.coarse_geometry();
  const hex8::NodeMatrix X = b.coarse_rest_positions();
  std::set<int> hit;
  for (int q = 0; q < 64; ++q) {
    // The point's rest position from the element's shape functions.
    const Vec3 x = X.transpose() * hex8::shapes(hex8::gauss_rule(4).points[q]);
    const int i = int(x.x() / kVoxel), j = int(x.y() / kVoxel), k = int(x.z() / kVoxel);
    const int v = i + 4 * (j + 4 * k);
    hit.insert(v);
    EXPECT_EQ(b.point_mu0[q], ids[v] ? pal[ids[v]]->shear_modulus() : 0.0) << q;
    EXPECT_EQ(b.point_lambda0[q], ids[v] ? pal[ids[v]]->lame_lambda() : 0.0) << q;
  }
  EXPECT_EQ(hit.size(), 64u);
  EXPECT_EQ(b.corner_nodes[0], -1);  // voxel 0 is void, and only it touches corner 0
  EXPECT_THROW(make_voxel_block(std::vector<int>(63, 1), pal, kVoxel, BlockMaterials{}), InputError);
  EXPECT_THROW(make_voxel_block(std::vector<int>(64, 3), pal, kVoxel, BlockMaterials{}), InputError);
  EXPECT_THROW(make_voxel_block(std::vector<int>(64, 0), pal, kVoxel, BlockMaterials{}), InputError);
}

// Periodic copies of copies: a block of 2 x 2 x 2 copies of a level-1
// block, relaxed among its periodic copies under a uniform strain, is the
// same body as the level-1 block among its own, so it stores exactly eight
// times the energy. This checks the 4^3 block's periodic classes, its
// corners and its load scaling against the 2^3 block's.
TEST(DdfemVoxelBlock, CopiesOfABlockStoreEightTimesItsPeriodicEnergy) {
  const auto pal = two_materials(1e5, 1e7);
  const BlockMaterials level1{1, 2, 2, 1, 2, 2, 1, 2};
  const FineBlock b2 = make_fine_block(level1, pal, kVoxel);
  const CoarseMaterialFit fit = level1_with_ids(level1);
  std::array<const CoarseMaterialFit*, 8> copies;
  copies.fill(&fit);
  const FineBlock b4 = make_voxel_block(level2_voxel_ids(copies), pal, kVoxel, BlockMaterials{1, 1, 1, 1, 1, 1, 1, 1});
  const PeriodicBlockSolver s2(b2, 1e-12), s4(b4, 1e-12);
  Mat3 G;
  G << 0.03, 0.01, -0.02, 0.0, -0.01, 0.015, 0.005, 0.02, 0.04;
  VecX w2, w4;
  const double E2 = s2.relax(affine_corners(b2, G), w2), E4 = s4.relax(affine_corners(b4, G), w4);
  ASSERT_TRUE(std::isfinite(E2));
  ASSERT_TRUE(std::isfinite(E4));
  EXPECT_GT(E2, 0);
  EXPECT_NEAR(E4 / (8 * E2), 1.0, 1e-9);
  // The uniform sample patterns are the same strains on both blocks.
  ForceSamplingOptions o;
  o.sphere_directions = 0;  // the three axes
  o.magnitudes = 1;
  const ForceSampleSet set2 = sample_periodic(b2, o), set4 = sample_periodic(b4, o);
  ASSERT_EQ(set2.patterns.size(), set4.patterns.size());
  int compared = 0;
  for (size_t s = 0; s < set2.samples.size() && s < set4.samples.size(); ++s) {
    const ForceSample &a = set2.samples[s], &b = set4.samples[s];
    ASSERT_EQ(a.pattern, b.pattern);
    const ForceKind kind = set2.patterns[a.pattern].kind;
    if (kind != ForceKind::stretch && kind != ForceKind::shear) continue;
    EXPECT_NEAR(b.energy / (8 * a.energy), 1.0, 1e-7) << s;
    ++compared;
  }
  EXPECT_EQ(compared, 2 * 2 * 3);  // stretch and shear along 3 axes, both signs
}

// A stiff fibre along y through a soft matrix: the points in the fibre's
// voxels stretch least along y, so their spring direction is y.
TEST(DdfemVoxelBlock, FibreVoxelsPointAlongTheFibre) {
  const auto pal = two_materials(1e5, 1e7);
  std::vector<int> ids(64, 1);
  for (int j = 0; j < 4; ++j) ids[1 + 4 * (j + 4 * 2)] = 2;  // voxels (1, j, 2)
  const FineBlock b = make_voxel_block(ids, pal, kVoxel, BlockMaterials{1, 1, 1, 1, 1, 1, 1, 1});
  AnisotropyOptions a;
  a.directions = 24;
  const std::vector<Vec3> d = periodic_point_directions(b, a);
  ASSERT_EQ(d.size(), 64u);
  int in_fibre = 0;
  for (int q = 0; q < 64; ++q) {
    if (b.point_mu0[q] != pal[2]->shear_modulus()) continue;
    ++in_fibre;
    EXPECT_GT(std::abs(d[q].y()), 0.99) << q << ": " << d[q].transpose();
  }
  EXPECT_EQ(in_fibre, 4);
}

}  // namespace
}  // namespace msfab
