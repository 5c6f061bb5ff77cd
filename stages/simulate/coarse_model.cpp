#include "coarse_model.hpp"

namespace msfab {

CoarseModel build_coarse_model(const Scene& scene, const VoxelMesh& fine, const CoarseningRequest& request) {
  CoarseModel m;
  static_cast<CoarsenedVoxels&>(m) = coarsen_voxels(scene.grid, scene.material_by_id, request);
  m.conditions = coarse_static_conditions(scene, fine, m.grid, m.mesh);
  return m;
}

}  // namespace msfab
