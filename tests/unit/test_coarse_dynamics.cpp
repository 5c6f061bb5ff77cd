// DDFEM in dynamics: a dynamics scene's design coarsened (layout painted
// inside the boxes, inertia and damping of each coarse element from its
// children) and a coarse run compared with the fine run frame by frame.
#include <gtest/gtest.h>

#include <string>

#include "core/errors.hpp"
#include "dynamics/coarse_dynamics.hpp"
#include "dynamics/dynamics_run.hpp"
#include "dynamics/dynamics_scene.hpp"
#include "dynamics/mass_matrix.hpp"
#include "io/config.hpp"

namespace msfab {
namespace {

// Two materials in a 1 cm checkerboard, one corner voxel carved out: every
// 2x2x2 block holds four of each, one block only seven voxels.
const char* kCheckerBar = R"(
name: checker-bar
materials:
  - {name: soft,  E: 1.0e5, nu: 0.3, density: 1000, damping_a: 2.0, damping_b: 1.0e-3}
  - {name: stiff, E: 1.0e6, nu: 0.3, density: 3000, damping_a: 0.0, damping_b: 1.0e-4}
geometry:
  voxel_size: 0.01
  boxes:
    - {material: soft, min: [0, 0, 0], max: [0.04, 0.08, 0.04]}
  layout:
    - {checker: {cell: 0.01, ids: [1, 2]}}
    - {box: {min: [0, 0, 0], max: [0.01, 0.01, 0.01]}, id: 0}
simulation: {time_step: 1.0e-3, duration: 0.01}
)";

DynamicsScene scene_of(const std::string& text, int level, const std::string& material = "naive") {
  CoarseningRequest request;
  request.level = level;
  request.material = material;
  return read_dynamics_scene(Config::from_string(text, "scene.yaml"), request);
}

double total_mass(const DynamicsScene& s) { return scalar_mass_matrix(s.model.mesh, s.model.density).sum(); }

TEST(CoarseDynamics, LayoutRepaintsOnlyInsideTheBoxes) {
  // An L of two boxes: the layout's fill must leave the empty corner empty.
  const std::string text = R"(
materials:
  - {name: a, E: 1.0e5, nu: 0.3, density: 1000}
  - {name: b, E: 1.0e6, nu: 0.3, density: 1000}
geometry:
  voxel_size: 0.01
  boxes:
    - {material: a, min: [0, 0, 0], max: [0.04, 0.02, 0.02]}
    - {material: a, min: [0, 0.02, 0], max: [0.02, 0.04, 0.02]}
  layout:
    - {fill: 2}
simulation: {time_step: 1.0e-3, duration: 0.01}
)";
  const DynamicsScene s = scene_of(text, 0);
  EXPECT_EQ(s.grid.count_solid(), 16u + 8u);
  for (int id : s.grid.ids) EXPECT_TRUE(id == 0 || id == 2);
  EXPECT_EQ(s.model.element_material_name.front(), "b");
}

TEST(CoarseDynamics, InertiaKeepsTheMassAndWeighsTheDamping) {
  const DynamicsScene fine = scene_of(kCheckerBar, 0);
  const DynamicsScene coarse = scene_of(kCheckerBar, 1);
  ASSERT_TRUE(coarse.coarsening);
  EXPECT_EQ(fine.grid.count_solid(), 4u * 8u * 4u - 1u);
  EXPECT_EQ(coarse.model.mesh.num_elements(), 2 * 4 * 2);
  EXPECT_NEAR(total_mass(coarse), total_mass(fine), 1e-12 * total_mass(fine));
  EXPECT_NEAR(total_mass(fine), (4 * 8 * 4 / 2 * 4000.0 - 1000.0) * 1e-6, 1e-12);
  // A full block: four soft, four stiff children.
  const int full = coarse.model.mesh.num_elements() - 1;
  EXPECT_NEAR(coarse.model.density[full], (4 * 1000.0 + 4 * 3000.0) / 8, 1e-9);
  EXPECT_NEAR(coarse.model.damping_a[full], 4 * 1000.0 * 2.0 / (4 * 1000.0 + 4 * 3000.0), 1e-12);
  EXPECT_NEAR(coarse.model.damping_b[full], (4 * 1e5 * 1e-3 + 4 * 1e6 * 1e-4) / (4 * 1e5 + 4 * 1e6), 1e-15);
  EXPECT_EQ(coarse.model.element_material_name[full], "soft");  // a tie goes to the first material
  // The carved block at the origin: three soft (the carved voxel was soft), four stiff.
  EXPECT_NEAR(coarse.model.density[0], (3 * 1000.0 + 4 * 3000.0) / 8, 1e-9);
  EXPECT_EQ(coarse.model.element_material_name[0], "stiff");
}

// A homogeneous cantilever plucked sideways and released.
const char* kCantilever = R"(
name: cantilever
materials:
  - {name: m, E: 2.0e5, nu: 0.3, density: 1000}
geometry:
  voxel_size: 0.005
  boxes:
    - {material: m, min: [0, 0, 0], max: [0.02, 0.08, 0.02]}
gravity: [0, 0, 0]
clamp: {min: [0, 0, 0], max: [0.02, 0, 0.02]}
pluck:
  region: {min: [0, 0.08, 0], max: [0.02, 0.08, 0.02]}
  force: [0.05, 0, 0]
simulation: {time_step: 2.0e-3, duration: 0.04, output_every: 4}
)";

TEST(CoarseDynamics, ErrorAgainstTheFineRunGrowsWithTheLevel) {
  const DynamicsScene fine = scene_of(kCantilever, 0);
  const DynamicsScene level1 = scene_of(kCantilever, 1);
  const DynamicsScene level2 = scene_of(kCantilever, 2);
  const Trajectory tf = run_dynamics_scene(fine), t1 = run_dynamics_scene(level1), t2 = run_dynamics_scene(level2);
  const TrajectoryDifference same = compare_with_fine(fine, tf, tf, "fine.h5");
  EXPECT_EQ(same.max_error, 0.0);
  const TrajectoryDifference d1 = compare_with_fine(level1, t1, tf, "fine.h5");
  const TrajectoryDifference d2 = compare_with_fine(level2, t2, tf, "fine.h5");
  ASSERT_EQ(d1.error.size(), tf.frames.size());
  EXPECT_EQ(d1.model_nodes, level1.model.mesh.num_nodes());
  // The swing is a few millimetres on an 8 cm bar: coarse models are close,
  // and closer with smaller elements (trilinear elements lock in bending).
  EXPECT_GT(d1.max_error, 1e-5);
  EXPECT_LT(d1.max_error, 5e-2);
  EXPECT_LT(d1.max_error, d2.max_error);
  EXPECT_LT(d1.max_center_of_mass_distance, d2.max_center_of_mass_distance);
}

TEST(CoarseDynamics, LoadsActOnTheFineNodesWithTheirTotalForceAndMoment) {
  // 15 voxels along the bar: the coarse grid is padded, so no coarse node
  // lies on the loaded face; the load still reaches the coarse mesh whole.
  std::string text = kCantilever;
  for (size_t at = text.find("0.08,"); at != std::string::npos; at = text.find("0.08,")) text.replace(at, 4, "0.075");
  const DynamicsScene fine = scene_of(text, 0);
  const DynamicsScene coarse = scene_of(text, 1);
  const VecX ff = region_force(fine, fine.load, "pluck"), fc = region_force(coarse, coarse.load, "pluck");
  ASSERT_EQ(fc.size(), coarse.model.mesh.num_dofs());
  Vec3 force_f = Vec3::Zero(), force_c = Vec3::Zero(), moment_f = Vec3::Zero(), moment_c = Vec3::Zero();
  for (int n = 0; n < fine.model.mesh.num_nodes(); ++n) {
    force_f += ff.segment<3>(3 * n);
    moment_f += fine.initial_positions.segment<3>(3 * n).cross(Vec3(ff.segment<3>(3 * n)));
  }
  for (int n = 0; n < coarse.model.mesh.num_nodes(); ++n) {
    force_c += fc.segment<3>(3 * n);
    moment_c += coarse.initial_positions.segment<3>(3 * n).cross(Vec3(fc.segment<3>(3 * n)));
  }
  EXPECT_LT((force_f - Vec3(0.05, 0, 0)).norm(), 1e-15);
  EXPECT_LT((force_c - force_f).norm(), 1e-15);
  EXPECT_LT((moment_c - moment_f).norm(), 1e-15);
  EXPECT_GT(moment_f.norm(), 1e-3);  // 0.05 N at 7.5 cm
}

TEST(CoarseDynamics, RefusesAReferenceOfAnotherSceneAndSeveralBodies) {
  const DynamicsScene fine = scene_of(kCantilever, 0);
  const DynamicsScene other = scene_of(kCheckerBar, 0);
  Trajectory t;
  t.rest_nodes = other.model.mesh.nodes;
  try {
    check_fine_reference(fine, t, "other.h5");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("other.h5"), std::string::npos) << e.what();
  }
  const std::string two_bodies = R"(
materials:
  - {name: m, E: 1.0e5, nu: 0.3, density: 1000}
geometry:
  voxel_size: 0.01
  boxes:
    - {material: m, body: a, min: [0, 0, 0], max: [0.02, 0.02, 0.02]}
    - {material: m, body: b, min: [0.02, 0, 0], max: [0.04, 0.02, 0.02]}
simulation: {time_step: 1.0e-3, duration: 0.01}
)";
  EXPECT_THROW(scene_of(two_bodies, 1), InputError);
  EXPECT_THROW(scene_of(kCantilever, 1, "ddfem"), InputError);  // no database
}

}  // namespace
}  // namespace msfab
