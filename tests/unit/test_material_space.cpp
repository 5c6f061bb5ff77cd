// Material property spaces of the gamut and their unit-cube normalization.
#include <gtest/gtest.h>

#include "core/errors.hpp"
#include "gamut/material_space.hpp"
#include "gamut/structure_ops.hpp"
#include "homog/periodic_homogenization.hpp"
#include "material/linear_isotropic.hpp"

namespace msfab {
namespace {

TEST(MaterialSpace, StiffBaseMaterialMapsToTheTopOfTheCube) {
  const MaterialSpace space(MaterialSpaceKind::cubic3d, 1e6);
  const VecX raw = space.properties(isotropic_tensor(1e6, 0.45), 1.0);
  EXPECT_NEAR(raw[0], 1e6, 1e-6);
  EXPECT_NEAR(raw[1], 0.45, 1e-12);
  EXPECT_NEAR(raw[2], 1e6 / 2.9, 1e-6);
  const VecX u = space.normalize(raw);
  EXPECT_NEAR(u[0], 1.0, 1e-12);
  EXPECT_NEAR(u[1], (0.45 + 1) / 1.5, 1e-12);
  EXPECT_NEAR(u[3], 1.0, 0);
  EXPECT_LT((space.denormalize(u) - raw).norm(), 1e-9 * raw.norm());
  // Four decades below E_stiff is the bottom of the cube.
  VecX soft = raw;
  soft[0] = 100;
  EXPECT_NEAR(space.normalize(soft)[0], 0.0, 1e-12);
  EXPECT_THROW(MaterialSpace::parse_kind("cubic"), InputError);
  EXPECT_EQ(MaterialSpace::parse_kind("orthotropic2d"), MaterialSpaceKind::orthotropic2d);
}

TEST(MaterialSpace, TensorsRoundTripThroughTheProperties) {
  // A mirrored random two-phase cell: cubic in 3D, square-symmetric in 2D.
  const std::vector<MaterialPtr> pal = {nullptr, std::make_shared<LinearIsotropic>(1e6, 0.45),
                                        std::make_shared<LinearIsotropic>(1e3, 0.45)};
  VoxelGrid c(6, 6, 6, 1.0 / 6, 1);
  for (std::size_t v = 0; v < c.size(); ++v) c.ids[v] = 1 + int((v * 7919) % 3 == 0);
  mirror_fundamental_domain(c);
  const HomogenizationResult r = homogenize(c, pal);
  const MaterialSpace cubic(MaterialSpaceKind::cubic3d, 1e6);
  const VecX p = cubic.properties(r.C, r.volume_fraction[1]);
  EXPECT_LT((cubic.tensor_3d(p) - r.C).norm(), 1e-8 * r.C.norm());
  VoxelGrid s(8, 8, 1, 1.0 / 8, 1);
  for (std::size_t v = 0; v < s.size(); ++v) s.ids[v] = 1 + int((v * 31) % 5 < 2);
  mirror_fundamental_domain(s);
  const Mat3 C2 = homogenize_plane_strain(s, pal).C;
  const MaterialSpace square(MaterialSpaceKind::cubic2d, 1e6), ortho(MaterialSpaceKind::orthotropic2d, 1e6);
  EXPECT_LT((square.tensor_2d(square.properties_2d(C2, 0.5)) - C2).norm(), 1e-8 * C2.norm());
  EXPECT_LT((ortho.tensor_2d(ortho.properties_2d(C2, 0.5)) - C2).norm(), 1e-8 * C2.norm());
  EXPECT_EQ(ortho.dimension(), 5);
}

}  // namespace
}  // namespace msfab
