#include "ddfem/coarsening_error.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "core/errors.hpp"
#include "core/timing.hpp"
#include "solve/cholmod_solver.hpp"

namespace msfab {
namespace {
using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
}

VecX interpolate_to_fine(const VoxelGrid& fine_grid, const VoxelMesh& fine_mesh, const CoarseGrid& coarse,
                         const VoxelMesh& coarse_mesh, const VecX& coarse_displacement) {
  if (coarse_displacement.size() != coarse_mesh.mesh.num_dofs())
    throw InputError("coarse displacement has " + std::to_string(coarse_displacement.size()) +
                     " entries, the coarse mesh " + std::to_string(coarse_mesh.mesh.num_dofs()) + " DOFs");
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
  return mean_vertex_error(fine_mesh.mesh, fine_displacement,
                           interpolate_to_fine(fine_grid, fine_mesh, coarse, coarse_mesh, coarse_displacement));
}

double mean_vertex_error(const HexMesh& fine_mesh, const VecX& fine_displacement, const VecX& interpolated) {
  const int n = fine_mesh.num_nodes();
  if (fine_displacement.size() != 3 * n || interpolated.size() != 3 * n)
    throw InputError("mean vertex error: displacements of " + std::to_string(fine_displacement.size()) + " and " +
                     std::to_string(interpolated.size()) + " entries for a fine mesh of " + std::to_string(3 * n) +
                     " DOFs");
  double sum = 0;
  for (int i = 0; i < n; ++i) sum += (fine_displacement.segment<3>(3 * i) - interpolated.segment<3>(3 * i)).norm();
  const double longest = (fine_mesh.bbox_max() - fine_mesh.bbox_min()).maxCoeff();
  return sum / n / longest;
}

CoarseErrorFloor coarse_error_floor(const VoxelGrid& fine_grid, const VoxelMesh& fine_mesh,
                                    const VecX& fine_displacement, const CoarseGrid& coarse,
                                    const VoxelMesh& coarse_mesh, const CoarseErrorFloorOptions& options) {
  return coarse_error_floor(coarse_to_fine_interpolation(fine_grid, fine_mesh, coarse, coarse_mesh), fine_mesh,
                            fine_displacement, options);
}

CoarseErrorFloor coarse_error_floor(const SpMat& P, const VoxelMesh& fine_mesh, const VecX& fine_displacement,
                                    const CoarseErrorFloorOptions& options) {
  const int n = fine_mesh.mesh.num_nodes();
  if (fine_displacement.size() != 3 * n || P.rows() != n)
    throw InputError("coarse error floor: " + std::to_string(fine_displacement.size()) + " displacements and " +
                     std::to_string(P.rows()) + " interpolation rows for a fine mesh of " + std::to_string(n) +
                     " nodes");
  if (options.max_iterations < 1 || !(options.gap_tolerance > 0))
    throw InputError("coarse error floor: max_iterations must be >= 1 and gap_tolerance > 0");
  const auto start = std::chrono::steady_clock::now();
  const double longest = (fine_mesh.mesh.bbox_max() - fine_mesh.mesh.bbox_min()).maxCoeff();
  const double scale = 1.0 / (double(n) * longest);
  const Eigen::Map<const Rows3> F(fine_displacement.data(), n, 3);

  // Residual norms below `floor_norm` get the weight of `floor_norm`: the
  // majorizer 1/||r|| is unbounded where the fit is exact.
  double mean_norm = 0;
  for (int i = 0; i < n; ++i) mean_norm += F.row(i).norm();
  mean_norm /= std::max(n, 1);
  const double floor_norm = 1e-9 * mean_norm + 1e-300;

  const SpMat Pt = P.transpose();
  LinearSolverOptions solver_options;
  solver_options.threads = 1;  // deterministic, and the factor is small
  CholmodSolver cholesky(solver_options);
  VecX weight = VecX::Ones(n);
  CoarseErrorFloor best;
  best.error = std::numeric_limits<double>::infinity();
  best.lower_bound = 0;
  Rows3 U(P.cols(), 3), R(n, 3);
  for (int it = 1; it <= options.max_iterations; ++it) {
    // Weighted least squares: P^T W P U = P^T W F. A tiny diagonal keeps
    // coarse nodes that no fine node reaches solvable.
    SpMat normal = Pt * weight.asDiagonal() * P;
    const double shift = 1e-14 * normal.diagonal().maxCoeff();
    for (int c = 0; c < normal.cols(); ++c) normal.coeffRef(c, c) += shift;
    if (it == 1) cholesky.analyze(normal);
    if (!cholesky.factorize(normal)) throw NumericalError("coarse error floor: weighted normal equations not definite");
    U = cholesky.solve_columns(MatX(Pt * (weight.asDiagonal() * F)));
    R = F - P * U;
    // Primal value, and the dual certificate L = W R, which satisfies
    // P^T L = 0 by the normal equations; scaled into ||L_n|| <= 1.
    double primal = 0, dual = 0, largest = 0;
    for (int i = 0; i < n; ++i) {
      const double r = R.row(i).norm();
      primal += r;
      dual += weight[i] * R.row(i).dot(F.row(i));
      largest = std::max(largest, weight[i] * r);
    }
    primal *= scale;
    dual = largest > 0 ? dual * scale / largest : 0.0;
    best.iterations = it;
    if (primal < best.error) {
      best.error = primal;
      best.coarse_displacement = Eigen::Map<const VecX>(U.data(), 3 * U.rows());
    }
    best.lower_bound = std::max(best.lower_bound, dual);
    if (best.error - best.lower_bound <= options.gap_tolerance * best.error) break;
    for (int i = 0; i < n; ++i) weight[i] = 1.0 / std::max(R.row(i).norm(), floor_norm);
  }
  best.lower_bound = std::min(best.lower_bound, best.error);
  best.seconds = seconds_since(start);
  return best;
}

}  // namespace msfab
