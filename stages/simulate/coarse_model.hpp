#pragma once
// Online coarsening for msfab-simulate (thesis §2.4): the shared voxel
// coarsening of ddfem/voxel_coarsening.hpp with the scene's static
// conditions carried onto the coarse mesh.
#include "ddfem/voxel_coarsening.hpp"
#include "scene/scene.hpp"

namespace msfab {

struct CoarseModel : CoarsenedVoxels {
  StaticConditions conditions;
};

// InputError for a bad request (coarsen_voxels) or conditions that select
// nothing on the coarse mesh.
CoarseModel build_coarse_model(const Scene& scene, const VoxelMesh& fine, const CoarseningRequest& request);

}  // namespace msfab
