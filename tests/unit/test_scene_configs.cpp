// Every static scene shipped in configs/scenes/ (and user/) reads without error or
// unknown keys, meshes, and has conditions that hold it (no free rigid
// motion, no load on void). The DDFEM mixed-block scenes also use the
// benchmark palette, coarsen without padding and mix materials inside their
// 2 x 2 x 2 blocks, which is what they are for.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <set>
#include <string>

#include "io/config.hpp"
#include "material/neo_hookean.hpp"
#include "scene/scene.hpp"

namespace msfab {
namespace {

namespace fs = std::filesystem;

const fs::path kFolder = fs::path(MSFAB_SOURCE_DIR) / "configs" / "scenes";

TEST(SceneConfigs, EveryShippedSceneReadsMeshesAndIsHeld) {
  int checked = 0;
  for (const auto& entry : fs::recursive_directory_iterator(kFolder)) {  // user/: parts from files
    if (entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(entry.path().string());
    const Config config = Config::load_file(entry.path().string());
    Scene scene;
    ASSERT_NO_THROW(scene = read_scene(config));
    EXPECT_NO_THROW(config.check_no_unknown_keys());
    const VoxelMesh vm = build_voxel_mesh(scene.grid, scene.material_by_id);
    EXPECT_GT(vm.mesh.num_elements(), 0);
    StaticConditions sc;
    EXPECT_NO_THROW(sc = build_static_conditions(scene, vm));
    EXPECT_GT(sc.dirichlet.count_fixed(), 0);
    ++checked;
  }
  EXPECT_GE(checked, 15);  // Table 2.2, bridges, demo bar, the mixed-block scenes, the user bracket twice
}

// Fraction of the all-solid 2 x 2 x 2 blocks that hold more than one material.
double mixed_block_fraction(const VoxelGrid& g) {
  int solid = 0, mixed = 0;
  for (int k = 0; k + 1 < g.nz; k += 2)
    for (int j = 0; j + 1 < g.ny; j += 2)
      for (int i = 0; i + 1 < g.nx; i += 2) {
        std::set<int> ids;
        for (int c = 0; c < 8; ++c) ids.insert(g.at(i + (c & 1), j + (c >> 1 & 1), k + (c >> 2 & 1)));
        if (ids.count(0)) continue;
        ++solid;
        mixed += ids.size() > 1;
      }
  return solid ? double(mixed) / solid : 0.0;
}

TEST(SceneConfigs, MixedBlockScenesUseTheBenchmarkPaletteAndMixInsideBlocks) {
  const struct {
    const char* name;
    double min_mixed;  // fraction of all-solid blocks holding two or more materials
    bool has_void;
  } scenes[] = {{"layers1", 0.99, false},
                {"checker", 0.99, false},
                {"random3", 0.99, false},
                {"skeleton", 0.25, true},
                {"sole", 0.25, false}};
  const double E[] = {1.0e5, 1.0e6, 1.0e7};
  for (const auto& expected : scenes) {
    SCOPED_TRACE(expected.name);
    const Config config = Config::load_file((kFolder / (std::string(expected.name) + ".yaml")).string());
    const Scene scene = read_scene(config);
    ASSERT_EQ(scene.palette.size(), 3u);
    for (int id = 1; id <= 3; ++id) {
      const auto* nh = dynamic_cast<const NeoHookean*>(scene.material_by_id.at(id).get());
      ASSERT_NE(nh, nullptr) << "id " << id;
      EXPECT_DOUBLE_EQ(nh->youngs_modulus(), E[id - 1]);
      EXPECT_DOUBLE_EQ(nh->poisson_ratio(), 0.45);
    }
    EXPECT_DOUBLE_EQ(scene.grid.voxel_size, 0.001);
    for (int n : {scene.grid.nx, scene.grid.ny, scene.grid.nz}) EXPECT_EQ(n % 4, 0) << "levels 1 and 2 need no padding";
    EXPECT_GE(mixed_block_fraction(scene.grid), expected.min_mixed);
    const bool has_void = std::count(scene.grid.ids.begin(), scene.grid.ids.end(), 0) > 0;
    EXPECT_EQ(has_void, expected.has_void);
    const int dofs = build_voxel_mesh(scene.grid, scene.material_by_id).mesh.num_dofs();
    EXPECT_GE(dofs, 5000);
    EXPECT_LE(dofs, 60000);
  }
}

}  // namespace
}  // namespace msfab
