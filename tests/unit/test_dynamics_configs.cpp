// Every dynamics scene shipped in configs/dynamics/ reads without error or
// unknown keys, and its preload region spreads exactly the force it names.
// Scenes whose material reads a calibrated dac_model artifact need a
// pipeline run first and are only checked for that reference.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "dynamics/dynamics_scene.hpp"
#include "io/config.hpp"

namespace msfab {
namespace {

namespace fs = std::filesystem;

bool reads_a_dac_model(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str().find("dac_model:") != std::string::npos;
}

TEST(DynamicsConfigs, EveryShippedSceneReadsAndLoadsItsRegion) {
  const fs::path folder = fs::path(MSFAB_SOURCE_DIR) / "configs" / "dynamics";
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(entry.path().string());
    if (reads_a_dac_model(entry.path())) continue;
    const Config config = Config::load_file(entry.path().string());
    const DynamicsScene scene = read_dynamics_scene(config);
    EXPECT_NO_THROW(config.check_no_unknown_keys());
    EXPECT_GT(scene.model.mesh.num_elements(), 0);
    EXPECT_GT(scene.duration, 0);
    if (scene.preload != Preload::kNone) {
      const VecX f = region_force(scene, scene.load, "preload");
      Vec3 total = Vec3::Zero();
      for (int i = 0; i < f.size() / 3; ++i) total += f.segment<3>(3 * i);
      EXPECT_LT((total - scene.load.force).norm(), 1e-12 * scene.load.force.norm());
    }
    ++checked;
  }
  EXPECT_GE(checked, 9);  // drops, rig, flipper, catapult, jumpers, plant
}

// The plant of the DAC benchmark: its pot is held, the rest is free to sway.
TEST(DynamicsConfigs, PlantIsHeldAtItsPotOnly) {
  const Config config = Config::load_file((fs::path(MSFAB_SOURCE_DIR) / "configs/dynamics/plant.yaml").string());
  const DynamicsScene scene = read_dynamics_scene(config);
  const HexMesh& mesh = scene.model.mesh;
  int held = 0;
  for (int node = 0; node < mesh.num_nodes(); ++node) {
    const bool fixed =
        scene.model.fixed[3 * node] && scene.model.fixed[3 * node + 1] && scene.model.fixed[3 * node + 2];
    const double z = scene.initial_positions(3 * node + 2);
    EXPECT_EQ(fixed, z <= 0.006 + 1e-12) << "node " << node << " at z = " << z;
    held += fixed;
  }
  EXPECT_EQ(held, 7 * 7 * 4);  // the 12 x 12 x 6 mm pot at 2 mm voxels
  EXPECT_EQ(scene.preload, Preload::kStaticPluck);
}

}  // namespace
}  // namespace msfab
