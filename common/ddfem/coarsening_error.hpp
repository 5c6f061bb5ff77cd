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
double mean_vertex_error(const HexMesh& fine_mesh, const VecX& fine_displacement, const VecX& interpolated);

// The smallest error any model on the coarse mesh can have: the error is a
// function of the coarse nodal displacements alone, so whatever the coarse
// materials (fitted, naive, averaged), no coarse solve can beat
//   min_U  mean_n || u_fine(n) - (P U)(n) || / longest side,
// the best trilinear fit of the fine displacements. It separates what the
// coarse mesh cannot represent from what the coarse materials get wrong.
// The coarse supports are not imposed, so it is a lower bound for any
// coarse model of the scene. Computed by iteratively reweighted least
// squares (a majorize-minimize method: the sum of norms never increases)
// and certified by the dual problem
//   max { sum_n L_n . u_fine(n) : ||L_n|| <= 1, P^T L = 0 },
// whose value at the last weights is a lower bound of the minimum.
struct CoarseErrorFloor {
  double error = 0;        // the error of the best coarse field found (an upper bound of the floor)
  double lower_bound = 0;  // the dual certificate: no coarse field has a smaller error
  int iterations = 0;
  double seconds = 0;
  VecX coarse_displacement;  // the best field found, 3 per coarse node, node-major
};
struct CoarseErrorFloorOptions {
  int max_iterations = 200;
  double gap_tolerance = 1e-3;  // stop when (error - lower_bound) <= gap_tolerance * error
};
CoarseErrorFloor coarse_error_floor(const VoxelGrid& fine_grid, const VoxelMesh& fine_mesh,
                                    const VecX& fine_displacement, const CoarseGrid& coarse,
                                    const VoxelMesh& coarse_mesh, const CoarseErrorFloorOptions& options = {});
// The same for an explicit (fine nodes) x (coarse nodes) interpolation.
CoarseErrorFloor coarse_error_floor(const SpMat& interpolation, const VoxelMesh& fine_mesh,
                                    const VecX& fine_displacement, const CoarseErrorFloorOptions& options = {});

}  // namespace msfab
