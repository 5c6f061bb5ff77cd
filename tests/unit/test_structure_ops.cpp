// Microstructure editing for the gamut sampler: symmetry, beams, clean-up.
#include <gtest/gtest.h>

#include <random>

#include "core/errors.hpp"
#include "gamut/structure_ops.hpp"
#include "homog/periodic_homogenization.hpp"
#include "material/linear_isotropic.hpp"

namespace msfab {
namespace {

VoxelGrid ops_random_cell(int n, int nz, int materials, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  VoxelGrid c(n, n, nz, 1.0 / n, 0);
  for (int& id : c.ids) id = 1 + int(rng() % materials);
  return c;
}

TEST(StructureOps, MirroringGivesCubicSymmetryAndACubicTensor) {
  VoxelGrid c = ops_random_cell(6, 6, 2, 1);
  EXPECT_FALSE(has_cubic_symmetry(c));
  mirror_fundamental_domain(c);
  EXPECT_TRUE(has_cubic_symmetry(c));
  // Every symmetry of the cube maps the cell onto itself: check two
  // generators directly (a reflection and an axis permutation).
  for (int k = 0; k < 6; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 6; ++i) {
        EXPECT_EQ(c.at(i, j, k), c.at(5 - i, j, k));
        EXPECT_EQ(c.at(i, j, k), c.at(k, i, j));
      }
  const std::vector<MaterialPtr> pal = {nullptr, std::make_shared<LinearIsotropic>(1e6, 0.3),
                                        std::make_shared<LinearIsotropic>(1e4, 0.45)};
  EXPECT_LT(cubic_deviation(homogenize(c, pal).C), 1e-9);
  // 2D: the square's symmetry; the plane tensor has C11 = C22 and no
  // shear coupling.
  VoxelGrid s = ops_random_cell(8, 1, 2, 2);
  mirror_fundamental_domain(s);
  EXPECT_TRUE(has_cubic_symmetry(s));
  const Mat3 C2 = homogenize_plane_strain(s, pal).C;
  EXPECT_NEAR(C2(0, 0), C2(1, 1), 1e-9 * C2(0, 0));
  EXPECT_NEAR(C2(0, 2), 0.0, 1e-9 * C2(0, 0));
  VoxelGrid bad(4, 4, 2, 1.0, 1);
  EXPECT_THROW(mirror_fundamental_domain(bad), InputError);
}

TEST(StructureOps, BeamPaintsTheVoxelsWithinItsRadius) {
  VoxelGrid c(8, 8, 8, 1.0, 0);
  // Along x through the cell's centre line y = z = 4: centres (j + 0.5, k + 0.5)
  // within 1 of (4, 4) are j, k in {3, 4}.
  EXPECT_EQ(paint_beam(c, Vec3(0, 4, 4), Vec3(8, 4, 4), 1.0, 2), 32);
  EXPECT_EQ(c.at(0, 3, 4), 2);
  EXPECT_EQ(c.at(0, 2, 4), 0);
  EXPECT_EQ(paint_beam(c, Vec3(0, 4, 4), Vec3(8, 4, 4), 1.0, 2), 0);  // already there
}

TEST(StructureOps, CleanupKeepsTheWrappingNetworkAndFillsCavities) {
  // Three orthogonal bars through the cell (one network, wraps along every
  // axis), a floating blob, and a solid block with a hole inside.
  VoxelGrid c(10, 10, 10, 1.0, 0);
  paint_beam(c, Vec3(0, 1, 1), Vec3(10, 1, 1), 0.8, 1);
  paint_beam(c, Vec3(1, 0, 1), Vec3(1, 10, 1), 0.8, 1);
  paint_beam(c, Vec3(1, 1, 0), Vec3(1, 1, 10), 0.8, 1);
  const int network = static_cast<int>(c.count_solid());
  c.at(6, 6, 6) = 2;  // floating
  c.at(6, 7, 6) = 2;
  // A hollow box attached to the network: solid shell 3..8 along y and z at x in 0..2, hole inside.
  for (int k = 1; k <= 5; ++k)
    for (int j = 1; j <= 5; ++j)
      for (int i = 0; i <= 2; ++i) c.at(i, j, k) = 1;
  c.at(1, 3, 3) = 0;  // an enclosed cavity
  const std::size_t before = c.count_solid();
  const CleanupReport r = clean_structure(c);
  EXPECT_EQ(r.removed_voxels, 2);
  EXPECT_EQ(r.filled_voxels, 1);
  EXPECT_EQ(c.at(6, 6, 6), 0);
  EXPECT_EQ(c.at(1, 3, 3), 1);
  EXPECT_EQ(c.count_solid(), before - 2 + 1);
  EXPECT_GT(static_cast<int>(c.count_solid()), network);
  // A bar along x alone wraps along one axis only: not a 3D network.
  VoxelGrid bar(6, 6, 6, 1.0, 0);
  paint_beam(bar, Vec3(0, 3, 3), Vec3(6, 3, 3), 1.0, 1);
  EXPECT_EQ(clean_structure(bar).removed_voxels, 4 * 6);
  EXPECT_EQ(bar.count_solid(), 0u);
  // 2D: a cross wraps in the plane and stays, and its (enclosed) holes stay open.
  VoxelGrid cross(8, 8, 1, 1.0, 0);
  paint_beam(cross, Vec3(0, 4, 0.5), Vec3(8, 4, 0.5), 1.0, 1);
  paint_beam(cross, Vec3(4, 0, 0.5), Vec3(4, 8, 0.5), 1.0, 1);
  const std::size_t cross_voxels = cross.count_solid();
  EXPECT_EQ(clean_structure(cross).removed_voxels, 0);
  EXPECT_EQ(cross.count_solid(), cross_voxels);
}

}  // namespace
}  // namespace msfab

namespace msfab {
namespace {

// Stiff bars of `width` voxels along x and y through the cell's middle, in void.
VoxelGrid bar_cross(int n, int nz, int width) {
  VoxelGrid c(n, n, nz, 1.0 / n, 0);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        if ((i >= n / 2 - width / 2 && i < n / 2 - width / 2 + width) ||
            (j >= n / 2 - width / 2 && j < n / 2 - width / 2 + width))
          c.at(i, j, k) = 1;
  return c;
}

TEST(StructureOps, ThinFeaturesAreTheVoxelsNoWindowOfTheirPhaseCovers) {
  // Bars 3 wide, gaps 13 wide: nothing below 3; below 4 the bars are thin.
  const VoxelGrid wide = bar_cross(16, 1, 3);
  EXPECT_EQ(thin_feature_voxels(wide, 1), 0);
  EXPECT_EQ(thin_feature_voxels(wide, 2), 0);
  EXPECT_EQ(thin_feature_voxels(wide, 3), 0);
  EXPECT_EQ(thin_feature_voxels(wide, 4), static_cast<std::int64_t>(wide.count_solid()));
  // A one-voxel bar is thin at 2; so is a one-voxel slit cut across a wide bar.
  EXPECT_EQ(thin_feature_voxels(bar_cross(16, 1, 1), 2), static_cast<std::int64_t>(bar_cross(16, 1, 1).count_solid()));
  VoxelGrid slit = bar_cross(16, 1, 4);
  for (int j = 6; j < 10; ++j) slit.at(2, j, 0) = 0;  // a gap of one voxel across the x bar
  EXPECT_EQ(thin_feature_voxels(slit, 2), 4);
  // 3D: the bars are slabs through z; a slab 2 thick passes 2 and fails 3.
  const VoxelGrid slabs = bar_cross(8, 8, 2);
  EXPECT_EQ(thin_feature_voxels(slabs, 2), 0);
  EXPECT_GT(thin_feature_voxels(slabs, 3), 0);
}

}  // namespace
}  // namespace msfab
