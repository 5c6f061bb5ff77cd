#include "fem/hex_element.hpp"

#include <cmath>

namespace msfab {

double hex_energy(const hex8::ElementGeometry& geo, const QuadratureMaterials& mat,
                  const hex8::NodeMatrix& x) {
  double e = 0;
  for (int q = 0; q < geo.size(); ++q) {
    double psi;
    mat[q].evaluate(hex8::deformation_gradient(x, geo.dNdX[q]), &psi, nullptr, nullptr);
    if (!std::isfinite(psi)) return kInfiniteEnergy;
    e += geo.weight[q] * psi;
  }
  return e;
}

double hex_evaluate(const hex8::ElementGeometry& geo, const QuadratureMaterials& mat,
                    const hex8::NodeMatrix& x, Vec24* gradient, Mat24* hessian) {
  double e = 0;
  if (gradient) gradient->setZero();
  if (hessian) hessian->setZero();
  Mat3 P;
  Mat9 H;
  for (int q = 0; q < geo.size(); ++q) {
    const hex8::NodeMatrix& D = geo.dNdX[q];
    const Mat3 F = hex8::deformation_gradient(x, D);
    double psi;
    mat[q].evaluate(F, &psi, gradient ? &P : nullptr, hessian ? &H : nullptr);
    if (!std::isfinite(psi)) return kInfiniteEnergy;
    const double w = geo.weight[q];
    e += w * psi;
    if (gradient) {
      // dE/dx_i = w P dN_i/dX
      const Eigen::Matrix<double, 3, 8> G = w * P * D.transpose();
      for (int i = 0; i < 8; ++i) gradient->segment<3>(3 * i) += G.col(i);
    }
    if (hessian) {
      // dF(a, c)/dx_i(a) = dN_i/dX_c, so with B the 9x24 map from nodal
      // displacements to flat F, K += w B^T H B. B has three non-zeros per
      // column; exploiting that costs ~2.4k flops per point instead of ~7k.
      Eigen::Matrix<double, 9, 24> HB;
      for (int i = 0; i < 8; ++i)
        for (int a = 0; a < 3; ++a)
          HB.col(3 * i + a) = H.col(a) * D(i, 0) + H.col(a + 3) * D(i, 1) + H.col(a + 6) * D(i, 2);
      for (int j = 0; j < 8; ++j) {
        const double d0 = w * D(j, 0), d1 = w * D(j, 1), d2 = w * D(j, 2);
        for (int b = 0; b < 3; ++b)
          hessian->row(3 * j + b) += d0 * HB.row(b) + d1 * HB.row(b + 3) + d2 * HB.row(b + 6);
      }
    }
  }
  return e;
}

}  // namespace msfab
