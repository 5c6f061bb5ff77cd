#include "ddfem/anisotropy.hpp"

#include "core/errors.hpp"
#include "ddfem/force_samples.hpp"

namespace msfab {

std::vector<Mat3> coarse_deformation_gradients(const hex8::ElementGeometry& coarse, const hex8::NodeMatrix& X,
                                               const Vec24& u) {
  hex8::NodeMatrix x = X;
  for (int c = 0; c < 8; ++c) x.row(c) += u.segment<3>(3 * c).transpose();
  std::vector<Mat3> F(coarse.size());
  for (int q = 0; q < coarse.size(); ++q) F[q] = hex8::deformation_gradient(x, coarse.dNdX[q]);
  return F;
}

Vec3 canonical_direction(const Vec3& v) {
  Eigen::Index a;
  v.cwiseAbs().maxCoeff(&a);
  return v[a] < 0 ? Vec3(-v) : v;
}

AnisotropyEstimate estimate_anisotropy(const FineBlock& block, const AnisotropyOptions& options) {
  if (options.directions < 3) throw InputError("anisotropy: at least 3 stretching directions are needed");
  if (!(options.strain > 0.0)) throw InputError("anisotropy: strain must be > 0");
  const BlockSolver solver(block, options.newton_tolerance);
  ForceSamplingOptions stretch_only;
  stretch_only.include_axes = false;
  stretch_only.sphere_directions = options.directions;
  stretch_only.seed = options.seed;
  std::vector<ForcePattern> stretches;
  for (ForcePattern& p : make_force_patterns(block, stretch_only))
    if (p.kind == ForceKind::stretch) stretches.push_back(std::move(p));

  // One load magnitude for all directions (unit-norm patterns): scaling each
  // direction to equal strain would erase the very signal sought.
  double peak = 0;
  for (const ForcePattern& p : stretches) peak = std::max(peak, solver.linear_peak_strain(p.force));
  const double load = options.strain / peak;

  const hex8::ElementGeometry coarse = block.coarse_geometry();
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  const int points = coarse.size();
  std::vector<std::vector<Vec3>> cloud(points);
  AnisotropyEstimate out;
  out.direction.resize(points);
  out.singular_values.resize(points);
  for (const ForcePattern& p : stretches) {
    ++out.solves;
    const BlockSolver::Solution s = solver.solve(load * p.force);
    if (!s.converged) {
      ++out.dropped;
      continue;
    }
    const auto F = coarse_deformation_gradients(coarse, X, solver.corner_displacements(s.x));
    for (int q = 0; q < points; ++q) {
      const double l = (F[q] * p.direction).norm();
      cloud[q].push_back(l * p.direction);
      cloud[q].push_back(-l * p.direction);
    }
  }
  if (cloud[0].size() < 6) throw NumericalError("anisotropy: too few stretching solves converged");
  for (int q = 0; q < points; ++q) {
    MatX M(cloud[q].size(), 3);
    for (size_t i = 0; i < cloud[q].size(); ++i) M.row(i) = cloud[q][i].transpose();
    Eigen::JacobiSVD<MatX> svd(M, Eigen::ComputeThinV);
    out.direction[q] = canonical_direction(svd.matrixV().col(2));
    out.singular_values[q] = svd.singularValues();
  }
  return out;
}

}  // namespace msfab
