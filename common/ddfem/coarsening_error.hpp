#pragma once
// Accuracy of a coarsened simulation against the fine one (thesis §2.5.2):
// the coarse displacements are trilinearly interpolated to the fine mesh's
// vertices, and the error is the mean vertex distance divided by the longest
// dimension of the fine rest bounding box.
#include "ddfem/coarse_grid.hpp"

namespace msfab {

// Coarse displacements (3 per coarse node, node-major) interpolated to the
// fine nodes.
VecX interpolate_to_fine(const VoxelGrid& fine_grid, const VoxelMesh& fine_mesh, const CoarseGrid& coarse,
                         const VoxelMesh& coarse_mesh, const VecX& coarse_displacement);

// mean_n || u_fine(n) - u_coarse_interp(n) || / max(bbox extent of the fine
// rest mesh). Displacements, not positions. Throws InputError on size
// mismatches.
double mean_vertex_error(const VoxelGrid& fine_grid, const VoxelMesh& fine_mesh, const VecX& fine_displacement,
                         const CoarseGrid& coarse, const VoxelMesh& coarse_mesh, const VecX& coarse_displacement);

// The same error for displacements already interpolated to the fine nodes.
double mean_vertex_error(const VoxelMesh& fine_mesh, const VecX& fine_displacement, const VecX& interpolated);

}  // namespace msfab
