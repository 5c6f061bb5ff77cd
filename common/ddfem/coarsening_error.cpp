#include "ddfem/coarsening_error.hpp"

#include "core/errors.hpp"

namespace msfab {
namespace {
using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
}

VecX interpolate_to_fine(const VoxelGrid& fine_grid, const VoxelMesh& fine_mesh, const CoarseGrid& coarse,
                         const VoxelMesh& coarse_mesh, const VecX& coarse_displacement) {
  if (coarse_displacement.size() != coarse_mesh.mesh.num_dofs())
    throw InputError("coarse displacement has " + std::to_string(coarse_displacement.size()) + " entries, the coarse mesh " +
                     std::to_string(coarse_mesh.mesh.num_dofs()) + " DOFs");
  const SpMat P = coarse_to_fine_interpolation(fine_grid, fine_mesh, coarse, coarse_mesh);
  VecX out(fine_mesh.mesh.num_dofs());
  Eigen::Map<Rows3>(out.data(), fine_mesh.mesh.num_nodes(), 3) =
      P * Eigen::Map<const Rows3>(coarse_displacement.data(), coarse_mesh.mesh.num_nodes(), 3);
  return out;
}

double mean_vertex_error(const VoxelGrid& fine_grid, const VoxelMesh& fine_mesh, const VecX& fine_displacement,
                         const CoarseGrid& coarse, const VoxelMesh& coarse_mesh, const VecX& coarse_displacement) {
  if (fine_displacement.size() != fine_mesh.mesh.num_dofs())
    throw InputError("fine displacement has " + std::to_string(fine_displacement.size()) + " entries, the fine mesh " +
                     std::to_string(fine_mesh.mesh.num_dofs()) + " DOFs");
  return mean_vertex_error(fine_mesh, fine_displacement,
                           interpolate_to_fine(fine_grid, fine_mesh, coarse, coarse_mesh, coarse_displacement));
}

double mean_vertex_error(const VoxelMesh& fine_mesh, const VecX& fine_displacement, const VecX& interpolated) {
  const int n = fine_mesh.mesh.num_nodes();
  if (fine_displacement.size() != 3 * n || interpolated.size() != 3 * n)
    throw InputError("mean vertex error: displacements of " + std::to_string(fine_displacement.size()) + " and " +
                     std::to_string(interpolated.size()) + " entries for a fine mesh of " + std::to_string(3 * n) +
                     " DOFs");
  double sum = 0;
  for (int i = 0; i < n; ++i) sum += (fine_displacement.segment<3>(3 * i) - interpolated.segment<3>(3 * i)).norm();
  const double longest = (fine_mesh.mesh.bbox_max() - fine_mesh.mesh.bbox_min()).maxCoeff();
  return sum / n / longest;
}

}  // namespace msfab
