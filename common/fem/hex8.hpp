#pragma once
// The 8-node trilinear hexahedron (thesis §2.1.1, Eq. 2.1-2.4).
//
// Node order follows Table 2.1: node i sits at natural coordinates
// (xi, eta, zeta) with xi = bit 2 of i, eta = bit 1, zeta = bit 0
// (0 -> -1, 1 -> +1). For an axis-aligned voxel this means node
// 4*dx + 2*dy + dz sits at corner (dx, dy, dz).
#include <vector>

#include "core/types.hpp"

namespace msfab::hex8 {

constexpr int kNodes = 8;
using NodeMatrix = Eigen::Matrix<double, kNodes, 3>;  // one row per node

// Natural coordinates of node i (entries +-1).
Vec3 natural_node(int i);

// N_i(chi) of Eq. 2.1.
double shape(int i, const Vec3& chi);
Eigen::Matrix<double, kNodes, 1> shapes(const Vec3& chi);

// dN_i/dchi as rows.
NodeMatrix shape_gradients(const Vec3& chi);

// Tensor-product Gauss-Legendre rule on [-1, 1]^3 with n points per axis
// (n = 1..4); n = 2 is the 8-point rule of the thesis, n = 4 the 64-point
// rule used by level-2 coarse elements.
struct QuadratureRule {
  std::vector<Vec3> points;
  std::vector<double> weights;
  int size() const { return static_cast<int>(points.size()); }
};
QuadratureRule gauss_rule(int points_per_axis);
// The element cut into cells_per_axis^3 equal sub-cubes, each with its own
// points_per_axis Gauss rule: cell-major, cells and the points inside each in
// the bit order of gauss_rule (first coordinate slowest). With 2^level cells
// the sub-cubes are the fine voxels of a coarse block, so a piecewise-constant
// material is integrated exactly over a polynomial field: the Galerkin coarse
// element (ddfem/baseline_coarsening.hpp).
QuadratureRule composite_gauss_rule(int cells_per_axis, int points_per_axis);

// Precomputed reference-configuration data of one element for one rule:
// spatial shape gradients dN/dX at each quadrature point and the weights
// w_q * det J_q. Throws InputError if the element is inverted or degenerate
// (det J <= 0 at a quadrature point).
struct ElementGeometry {
  std::vector<NodeMatrix> dNdX;
  std::vector<double> weight;
  // Empty for the plain trilinear element. Otherwise the element has three
  // incompatible bubble modes 1 - chi_k^2 per displacement component
  // (Wilson; Taylor's form that passes the patch test), whose 9 amplitudes
  // A are condensed inside the element: F_q = F_q(x) + A G_q^T with
  // row k of enhanced[q] the spatial gradient of bubble k at point q
  // (hex_element.hpp). A point without bubbles (the centre) has zeros.
  std::vector<Mat3> enhanced;
  int size() const { return static_cast<int>(weight.size()); }
  bool has_enhanced_modes() const { return !enhanced.empty(); }
};
ElementGeometry element_geometry(const NodeMatrix& X, const QuadratureRule& rule);
// The same with the bubble modes: G_q = (detJ_0 / detJ_q) J_0^{-T}-mapped
// gradients of 1 - chi_k^2 (J_0 the Jacobian at the centre), so that they
// integrate to zero over the element and constant strains stay exact.
ElementGeometry enhanced_element_geometry(const NodeMatrix& X, const QuadratureRule& rule);
// `geo` with one more point: the element centre, weighted by the element's
// volume. A material placed there sees the centre's deformation gradient, as
// the volumetric point of selective reduced integration does; DDFEM coarse
// materials may carry a fitted volumetric term there (ddfem/coarse_fit.hpp).
ElementGeometry with_centre_point(const ElementGeometry& geo, const NodeMatrix& X);

// F = sum_i x_i (dN_i/dX)^T (Eq. 2.4 written for positions x = X + u).
inline Mat3 deformation_gradient(const NodeMatrix& x, const NodeMatrix& dNdX) { return x.transpose() * dNdX; }

}  // namespace msfab::hex8
