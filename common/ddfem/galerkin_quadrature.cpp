#include "ddfem/galerkin_quadrature.hpp"

#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include "ddfem/nnls.hpp"

namespace msfab {

std::vector<std::array<int, 3>> hex_stiffness_monomials() {
  // Monomials of d(phi)/d(chi_k): trilinear shape functions give chi_i^p chi_j^q
  // (i, j the other two axes, p, q in {0, 1}), the bubble 1 - chi_k^2 gives chi_k.
  std::array<std::vector<std::array<int, 3>>, 3> gradient;
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    for (int p = 0; p < 2; ++p)
      for (int q = 0; q < 2; ++q) {
        std::array<int, 3> a{0, 0, 0};
        a[i] = p;
        a[j] = q;
        gradient[k].push_back(a);
      }
    std::array<int, 3> bubble{0, 0, 0};
    bubble[k] = 1;
    gradient[k].push_back(bubble);
  }
  std::set<std::array<int, 3>> products;
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l)
      for (const auto& a : gradient[k])
        for (const auto& b : gradient[l]) products.insert({a[0] + b[0], a[1] + b[1], a[2] + b[2]});
  return {products.begin(), products.end()};
}

ReducedRule reduced_stiffness_rule(const hex8::QuadratureRule& full, const std::vector<int>& group) {
  if (group.size() != full.points.size())
    throw std::invalid_argument("reduced_stiffness_rule: one group per point expected");
  const std::vector<std::array<int, 3>> monomials = hex_stiffness_monomials();
  const int rows = static_cast<int>(monomials.size());
  auto values = [&](const Vec3& chi) {
    VecX v(rows);
    for (int r = 0; r < rows; ++r)
      v[r] = std::pow(chi[0], monomials[r][0]) * std::pow(chi[1], monomials[r][1]) * std::pow(chi[2], monomials[r][2]);
    return v;
  };
  std::map<int, std::vector<int>> members;
  for (int q = 0; q < full.size(); ++q)
    if (group[q] >= 0) members[group[q]].push_back(q);

  std::vector<double> weight(full.size(), 0.0);
  for (const auto& [g, points] : members) {
    const int n = static_cast<int>(points.size());
    MatX A(rows, n);
    VecX moments = VecX::Zero(rows);
    for (int k = 0; k < n; ++k) {
      A.col(k) = values(full.points[points[k]]);
      moments += full.weights[points[k]] * A.col(k);
    }
    // Columns are monomials in [-1, 1] led by 1: of one scale already.
    const NnlsResult fit = solve_nnls(A, moments);
    const bool exact = (A * fit.x - moments).norm() <= 1e-11 * moments.norm();
    for (int k = 0; k < n; ++k) weight[points[k]] = exact ? fit.x[k] : full.weights[points[k]];
  }
  ReducedRule reduced;
  for (int q = 0; q < full.size(); ++q)
    if (group[q] >= 0 && weight[q] > 0) {
      reduced.rule.points.push_back(full.points[q]);
      reduced.rule.weights.push_back(weight[q]);
      reduced.source.push_back(q);
    }
  return reduced;
}

}  // namespace msfab
