#pragma once
// The database builder's configuration (docs/ddfem.md, "Building").
#include <string>
#include <vector>

#include "ddfem/coarse_db.hpp"
#include "io/config.hpp"

namespace msfab {

struct BuildOptions {
  std::vector<DbMaterial> materials;  // palette ids 1..n (level 1)
  // Fit blocks with void children too (level 1, periodic sampling): the
  // thesis's palettes always include void (§2.2). docs/ddfem.md.
  bool void_children = false;
  // Level 2 (§2.3.5): a level-1 database, compressed to at most 1024
  // coarse materials, is the palette; the hierarchy's options.
  std::string base_database;
  HierarchyOptions hierarchy;
  // Level 2: sample each final block on its 4 x 4 x 4 fine voxels (the
  // palette materials of its children's level-1 combinations) instead of on
  // 2 x 2 x 2 level-1 elements with their fitted materials, so a level-1
  // fit's error is not fitted into level 2 (`level2.samples: voxels`).
  bool level2_voxel_samples = false;
  double voxel_size = 1e-3;  // of the sampled block; the fit is scale-invariant
  CoarseFitOptions fit;
  bool use_symmetry = true;  // fit one block per cube-symmetry orbit
  int orbits_per_round = 8;  // work between checkpoints, over all ranks
};

// Reads and validates; InputError naming the key on bad input.
BuildOptions read_build_options(const Config& config);

inline constexpr const char* kDefaultBuildConfig = R"(
# The tiny palette of the demo and the tests: two Neo-Hookean materials
# (ids 1, 2) plus void, few samples. docs/ddfem.md lists every key.
palette:
  - {name: soft,  E: 1.0e5, nu: 0.45, density: 1000}
  - {name: stiff, E: 1.0e7, nu: 0.45, density: 1200}
voxel_size: 0.001
sampling: {sphere_directions: 2, magnitudes: 3, max_strain: 0.15, seed: 1}
anisotropy: {directions: 12, strain: 0.05, seed: 7}
fit: {regularization: 0.02, heldout_fraction: 0.2, split_seed: 11, anisotropic: true, pinch_weight: 0.1}
symmetry: true
orbits_per_round: 4
)";

}  // namespace msfab
