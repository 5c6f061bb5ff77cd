// Bodies that ride along in a static preload: which bodies are passengers,
// and that a passenger follows the rigid motion of what it rests on.
#include <gtest/gtest.h>

#include <cmath>

#include "core/errors.hpp"
#include "dynamics/dynamics_scene.hpp"
#include "dynamics/passenger_bodies.hpp"

using namespace msfab;

namespace {

// A clamped 3x2x1 plate with a 1x1x1 cube lying on it, and a load region at
// the plate's free end.
DynamicsScene plate_and_cube(const std::string& extra = "") {
  const std::string yaml = R"(
name: plate-and-cube
materials:
  - {name: stiff, E: 1.0e9, nu: 0.3, density: 1000}
geometry:
  voxel_size: 0.01
  boxes:
    - {material: stiff, body: plate, min: [0, 0, 0], max: [0.03, 0.02, 0.01]}
    - {material: stiff, body: cube, min: [0.01, 0, 0.01], max: [0.02, 0.01, 0.02]}
clamp: {min: [0, 0, 0], max: [0, 0.02, 0.01]}
pluck: {region: {min: [0.03, 0, 0], max: [0.03, 0.02, 0.01]}, force: [0, 0, -1]}
simulation: {time_step: 1.0e-4, duration: 0.001}
)" + extra;
  return read_dynamics_scene(Config::from_string(yaml, "plate_and_cube.yaml"));
}

}  // namespace

TEST(PassengerBodies, OnlyAnUnclampedUnloadedBodyRidesAlong) {
  const DynamicsScene scene = plate_and_cube();
  ASSERT_EQ(scene.body_names, (std::vector<std::string>{"plate", "cube"}));
  const VecX load = region_force(scene, scene.load, "pluck");
  EXPECT_EQ(passenger_bodies(scene, load), (std::vector<char>{0, 1}));
  const std::vector<char> dofs = passenger_dofs(scene, {0, 1});
  int riding = 0;
  for (char d : dofs) riding += d;
  EXPECT_EQ(riding, 3 * 8);  // the cube's eight nodes, separate from the plate's
}

TEST(PassengerBodies, APassengerFollowsTheRigidMotionOfItsSupport) {
  const DynamicsScene scene = plate_and_cube();
  const VecX& x0 = scene.initial_positions;
  // Move everything by one rigid motion, then scramble the cube: carrying
  // must restore the cube to the same rigid motion.
  const Mat3 R = Eigen::AngleAxisd(0.3, Vec3(0.2, 1.0, -0.4).normalized()).toRotationMatrix();
  const Vec3 t(0.004, -0.002, 0.007);
  VecX moved = x0;
  for (Eigen::Index i = 0; i < x0.size() / 3; ++i) moved.segment<3>(3 * i) = R * x0.segment<3>(3 * i) + t;
  VecX solved = moved;
  std::vector<int> node_body(scene.model.mesh.num_nodes(), 0);
  for (int e = 0; e < scene.model.mesh.num_elements(); ++e)
    for (int n : scene.model.mesh.elements[e]) node_body[n] = scene.element_body[e];
  for (int i = 0; i < scene.model.mesh.num_nodes(); ++i)
    if (node_body[i] == 1) solved.segment<3>(3 * i) = x0.segment<3>(3 * i);  // held during the solve
  std::vector<std::string> notes;
  const VecX carried = carry_passengers(scene, {0, 1}, x0, solved, &notes);
  EXPECT_LT((carried - moved).cwiseAbs().maxCoeff(), 1e-14);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("cube carried with its support (4 nodes"), std::string::npos) << notes[0];
}

TEST(PassengerBodies, OverlappingBodiesAreRejected) {
  const std::string yaml = R"(
materials:
  - {name: stiff, E: 1.0e9, nu: 0.3, density: 1000}
geometry:
  voxel_size: 0.01
  boxes:
    - {material: stiff, body: plate, min: [0, 0, 0], max: [0.03, 0.02, 0.01]}
    - {material: stiff, body: cube, min: [0.01, 0, 0], max: [0.02, 0.01, 0.02]}
simulation: {time_step: 1.0e-4, duration: 0.001}
)";
  try {
    read_dynamics_scene(Config::from_string(yaml, "overlap.yaml"));
    FAIL() << "overlapping bodies were accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("geometry.boxes[1]"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("overlaps a box of body 'plate'"), std::string::npos) << e.what();
  }
}
