// Voxel painting helpers and scene reading / conditions.
#include <gtest/gtest.h>

#include <cmath>

#include "core/errors.hpp"
#include "fem/voxel_shapes.hpp"
#include "scene/scene.hpp"

using namespace msfab;

TEST(VoxelShapes, BoxLayersCylinderAndHelixPaintTheRightVoxels) {
  VoxelGrid g(10, 10, 10, 0.1, 0);
  paint_box(g, Vec3(0, 0, 0), Vec3(0.5, 1, 1), 1);
  EXPECT_EQ(g.count_solid(), 500u);
  paint_layers(g, 2, {0.2, 0.3}, {1, 2});  // z layers: 2 voxels of 1, 3 of 2, repeating
  EXPECT_EQ(g.at(0, 0, 0), 1);
  EXPECT_EQ(g.at(0, 0, 1), 1);
  EXPECT_EQ(g.at(0, 0, 2), 2);
  EXPECT_EQ(g.at(5, 5, 4), 2);
  EXPECT_EQ(g.at(5, 5, 5), 1);
  VoxelGrid c(20, 20, 4, 0.1, 0);
  paint_cylinder(c, 2, Vec3(1, 1, 0), 0.5, 0.0, 0.2, 3);
  // Area pi r^2 = 0.785 -> about 78.5 voxels per layer, two layers.
  EXPECT_NEAR(double(c.count_solid()) / 2, 78.5, 6.0);
  EXPECT_EQ(c.at(10, 10, 0), 3);
  EXPECT_EQ(c.at(10, 10, 3), 0);
  VoxelGrid h(20, 40, 20, 0.05, 0);
  paint_helical_fibers(h, 1, Vec3(0.5, 0, 0.5), 0.3, 2.0, 0.08, 2, 1);
  // Two fibres of radius 0.08 and length ~ helix arc length over y in [0, 2].
  const double arc = std::sqrt(std::pow(2 * M_PI * 0.3, 2) + 4.0);
  const double expected = 2 * M_PI * 0.08 * 0.08 * arc / std::pow(0.05, 3);
  EXPECT_NEAR(double(h.count_solid()), expected, 0.25 * expected);
  // For axis y the helix starts along z: fibre 0 passes through (0.5, 0, 0.5 + 0.3).
  EXPECT_EQ(h.at(9, 0, 15) + h.at(10, 0, 15), 2);
  EXPECT_THROW(paint_layers(g, 3, {0.1}, {1}), InputError);
}

namespace {
const char* kScene = R"(
name: t
grid: {size: [4, 2, 2], voxel_size: 0.5}
materials:
  - {id: 1, model: neo-hookean, E: 1.0e6, nu: 0.3}
layout: [{fill: 1}]
boundary:
  - {region: {face: xmin}, fix: [x, y, z]}
loads:
  - {region: {face: xmax}, traction: [0, 0, -100]}
)";
}

TEST(Scene, FaceLoadsIntegrateTractionOverTheFace) {
  Config cfg = Config::from_string(kScene, "test");
  const Scene s = read_scene(cfg);
  cfg.check_no_unknown_keys();
  const VoxelMesh vm = build_voxel_mesh(s.grid, s.material_by_id);
  const StaticConditions sc = build_static_conditions(s, vm);
  double fz = 0;
  for (int n = 0; n < vm.mesh.num_nodes(); ++n) fz += sc.force[3 * n + 2];
  EXPECT_NEAR(fz, -100 * 1.0 * 1.0, 1e-12);  // face is 1 m x 1 m
  EXPECT_EQ(sc.dirichlet.count_fixed(), 3 * 9);  // 3 x 3 nodes on x = 0
}

TEST(Scene, RigidMotionLeftFreeIsRejected) {
  Config cfg = Config::from_string(kScene, "test");
  cfg.apply_override("boundary[0].fix=[z]");
  const Scene s = read_scene(cfg);
  const VoxelMesh vm = build_voxel_mesh(s.grid, s.material_by_id);
  EXPECT_THROW(build_static_conditions(s, vm), InputError);
}

TEST(Scene, DisconnectedPartWithoutSupportIsRejected) {
  Config cfg = Config::from_string(kScene, "test");
  cfg.apply_override("layout=[{fill: 1}, {box: {min: [1.0, 0, 0], max: [1.5, 1, 1]}, id: 0}]");
  const Scene s = read_scene(cfg);
  const VoxelMesh vm = build_voxel_mesh(s.grid, s.material_by_id);
  try {
    build_static_conditions(s, vm);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("disconnected part"), std::string::npos) << e.what();
  }
}

TEST(Scene, RotationConditionTurnsTheFace) {
  Config cfg = Config::from_string(kScene, "test");
  cfg.apply_override("boundary=[{region: {face: xmin}, rotation: {axis: [1, 0, 0], center: [0, 0.5, 0.5], angle_deg: 90}}]");
  const Scene s = read_scene(cfg);
  const VoxelMesh vm = build_voxel_mesh(s.grid, s.material_by_id);
  const StaticConditions sc = build_static_conditions(s, vm);
  // The node at (0, 1, 0.5) goes to (0, 0.5, 1) under a quarter turn about x.
  for (int n = 0; n < vm.mesh.num_nodes(); ++n) {
    const Vec3 X = vm.mesh.nodes.row(n).transpose();
    if ((X - Vec3(0, 1, 0.5)).norm() < 1e-12) {
      const Vec3 u = sc.dirichlet.displacement.segment<3>(3 * n);
      EXPECT_NEAR((X + u - Vec3(0, 0.5, 1)).norm(), 0.0, 1e-12);
    }
  }
}
