#include "dynamics/mass_matrix.hpp"

#include <cmath>
#include <string>

#include "core/errors.hpp"

namespace msfab {

namespace {

SpMat integrate_mass(const HexMesh& mesh, const std::vector<double>& density, bool allow_zero) {
  if (density.size() != static_cast<size_t>(mesh.num_elements()))
    throw InputError("mass matrix: " + std::to_string(density.size()) + " densities for " +
                     std::to_string(mesh.num_elements()) + " elements");
  const hex8::QuadratureRule rule = hex8::gauss_rule(2);
  std::vector<Eigen::Matrix<double, 8, 1>> N(rule.size());
  for (int q = 0; q < rule.size(); ++q) N[q] = hex8::shapes(rule.points[q]);

  std::vector<Eigen::Triplet<double, int>> triplets;
  triplets.reserve(size_t(64) * mesh.num_elements());
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const double rho = density[e];
    if (!(allow_zero ? rho >= 0 : rho > 0) || !std::isfinite(rho))
      throw InputError("mass matrix: element " + std::to_string(e) + " has density " + std::to_string(rho) +
                       " (must be positive)");
    // The element's Jacobian determinants at the 2-point rule (the stored
    // geometry may use another rule, so recompute them here).
    const hex8::NodeMatrix X = mesh.element_rest_positions(e);
    Eigen::Matrix<double, 8, 8> Me = Eigen::Matrix<double, 8, 8>::Zero();
    for (int q = 0; q < rule.size(); ++q) {
      const double detJ = (X.transpose() * hex8::shape_gradients(rule.points[q])).determinant();
      if (!(detJ > 0)) throw InputError("mass matrix: element " + std::to_string(e) + " is inverted or degenerate");
      Me.noalias() += (rho * rule.weights[q] * detJ) * N[q] * N[q].transpose();
    }
    const auto& nodes = mesh.elements[e];
    for (int i = 0; i < 8; ++i)
      for (int j = 0; j < 8; ++j) triplets.emplace_back(nodes[i], nodes[j], Me(i, j));
  }
  SpMat M(mesh.num_nodes(), mesh.num_nodes());
  M.setFromTriplets(triplets.begin(), triplets.end());  // sums duplicates in a fixed order
  return M;
}

}  // namespace

SpMat scalar_mass_matrix(const HexMesh& mesh, const std::vector<double>& density) {
  return integrate_mass(mesh, density, false);
}

SpMat weighted_mass_matrix(const HexMesh& mesh, const std::vector<double>& weight) {
  return integrate_mass(mesh, weight, true);
}

SpMat expand_to_dofs(const SpMat& m) {
  std::vector<Eigen::Triplet<double, int>> triplets;
  triplets.reserve(size_t(3) * m.nonZeros());
  for (int j = 0; j < m.outerSize(); ++j)
    for (SpMat::InnerIterator it(m, j); it; ++it)
      for (int a = 0; a < 3; ++a) triplets.emplace_back(3 * it.row() + a, 3 * j + a, it.value());
  SpMat M(3 * m.rows(), 3 * m.cols());
  M.setFromTriplets(triplets.begin(), triplets.end());
  return M;
}

MassProperties mass_properties(const SpMat& m, const NodeArray& X) {
  MassProperties p;
  VecX row_sum = VecX::Zero(m.rows());
  for (int j = 0; j < m.outerSize(); ++j)
    for (SpMat::InnerIterator it(m, j); it; ++it) row_sum(it.row()) += it.value();
  p.mass = row_sum.sum();
  p.center = (X.transpose() * row_sum) / p.mass;
  for (int j = 0; j < m.outerSize(); ++j)
    for (SpMat::InnerIterator it(m, j); it; ++it) {
      const Vec3 xi = X.row(it.row()).transpose() - p.center;
      const Vec3 xj = X.row(j).transpose() - p.center;
      p.second_moment += it.value() * xi * xj.transpose();
    }
  return p;
}

}  // namespace msfab
