#include "fem/hex8.hpp"

#include <cmath>
#include <sstream>
#include <string>

#include "core/errors.hpp"

namespace msfab::hex8 {

Vec3 natural_node(int i) { return Vec3((i & 4) ? 1.0 : -1.0, (i & 2) ? 1.0 : -1.0, (i & 1) ? 1.0 : -1.0); }

double shape(int i, const Vec3& chi) {
  const Vec3 c = natural_node(i);
  return 0.125 * (1 + c.x() * chi.x()) * (1 + c.y() * chi.y()) * (1 + c.z() * chi.z());
}

Eigen::Matrix<double, kNodes, 1> shapes(const Vec3& chi) {
  Eigen::Matrix<double, kNodes, 1> N;
  for (int i = 0; i < kNodes; ++i) N(i) = shape(i, chi);
  return N;
}

NodeMatrix shape_gradients(const Vec3& chi) {
  NodeMatrix d;
  for (int i = 0; i < kNodes; ++i) {
    const Vec3 c = natural_node(i);
    const double a = 1 + c.x() * chi.x(), b = 1 + c.y() * chi.y(), e = 1 + c.z() * chi.z();
    d(i, 0) = 0.125 * c.x() * b * e;
    d(i, 1) = 0.125 * a * c.y() * e;
    d(i, 2) = 0.125 * a * b * c.z();
  }
  return d;
}

QuadratureRule gauss_rule(int n) {
  std::vector<double> x, w;
  switch (n) {
    case 1:
      x = {0.0};
      w = {2.0};
      break;
    case 2:
      x = {-1 / std::sqrt(3.0), 1 / std::sqrt(3.0)};
      w = {1.0, 1.0};
      break;
    case 3: {
      const double a = std::sqrt(0.6);
      x = {-a, 0.0, a};
      w = {5.0 / 9, 8.0 / 9, 5.0 / 9};
      break;
    }
    case 4: {
      const double s = 2.0 / 7 * std::sqrt(6.0 / 5);
      const double a = std::sqrt(3.0 / 7 - s), b = std::sqrt(3.0 / 7 + s);
      const double wa = (18 + std::sqrt(30.0)) / 36, wb = (18 - std::sqrt(30.0)) / 36;
      x = {-b, -a, a, b};
      w = {wb, wa, wa, wb};
      break;
    }
    default: {
      std::ostringstream msg;
      msg << "Gauss rule with " << n << " points per axis is not available (1..4)";
      throw InputError(msg.str());
    }
  }
  QuadratureRule rule;
  // Same bit order as the nodes: the first coordinate varies slowest.
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        rule.points.emplace_back(x[i], x[j], x[k]);
        rule.weights.push_back(w[i] * w[j] * w[k]);
      }
  return rule;
}

QuadratureRule composite_gauss_rule(int cells, int n) {
  if (cells < 1) throw InputError("composite Gauss rule: cells per axis must be >= 1, got " + std::to_string(cells));
  const QuadratureRule unit = gauss_rule(n);
  const double half = 1.0 / cells;
  QuadratureRule rule;
  for (int a = 0; a < cells; ++a)
    for (int b = 0; b < cells; ++b)
      for (int c = 0; c < cells; ++c) {
        const Vec3 centre = Vec3(2 * a + 1, 2 * b + 1, 2 * c + 1) * half - Vec3::Ones();
        for (int q = 0; q < unit.size(); ++q) {
          rule.points.push_back(centre + half * unit.points[q]);
          rule.weights.push_back(unit.weights[q] * half * half * half);
        }
      }
  return rule;
}

ElementGeometry element_geometry(const NodeMatrix& X, const QuadratureRule& rule) {
  ElementGeometry g;
  g.dNdX.resize(rule.size());
  g.weight.resize(rule.size());
  for (int q = 0; q < rule.size(); ++q) {
    const NodeMatrix dNdchi = shape_gradients(rule.points[q]);
    const Mat3 J = X.transpose() * dNdchi;  // dX/dchi
    const double detJ = J.determinant();
    if (!(detJ > 0)) {
      std::ostringstream msg;
      msg << "hexahedron is inverted or degenerate (det J = " << detJ << " at quadrature point " << q
          << "); check the node order (thesis Table 2.1) and coordinates";
      throw InputError(msg.str());
    }
    g.dNdX[q] = dNdchi * J.inverse();
    g.weight[q] = rule.weights[q] * detJ;
  }
  return g;
}

ElementGeometry enhanced_element_geometry(const NodeMatrix& X, const QuadratureRule& rule) {
  ElementGeometry g = element_geometry(X, rule);
  const Mat3 J0 = X.transpose() * shape_gradients(Vec3::Zero());
  const double det0 = J0.determinant();
  const Mat3 J0_inverse = J0.inverse();
  g.enhanced.resize(rule.size());
  for (int q = 0; q < rule.size(); ++q) {
    const double detJ = (X.transpose() * shape_gradients(rule.points[q])).determinant();
    // d(1 - chi_k^2)/dchi = -2 chi_k e_k; spatial: J0^-T of it, row k.
    for (int k = 0; k < 3; ++k) g.enhanced[q].row(k) = (det0 / detJ) * (-2.0 * rule.points[q][k]) * J0_inverse.row(k);
  }
  return g;
}

ElementGeometry with_centre_point(const ElementGeometry& geo, const NodeMatrix& X) {
  const ElementGeometry centre = element_geometry(X, gauss_rule(1));
  ElementGeometry g = geo;
  g.dNdX.push_back(centre.dNdX[0]);
  g.weight.push_back(centre.weight[0]);
  if (g.has_enhanced_modes()) g.enhanced.push_back(Mat3::Zero());  // the bubbles' gradients vanish there
  return g;
}

}  // namespace msfab::hex8
