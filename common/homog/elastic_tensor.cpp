#include "homog/elastic_tensor.hpp"

namespace msfab {

Mat3 strain_tensor(const Vec6& e) {
  Mat3 s;
  s << e[0], 0.5 * e[5], 0.5 * e[4],  //
      0.5 * e[5], e[1], 0.5 * e[3],   //
      0.5 * e[4], 0.5 * e[3], e[2];
  return s;
}

Mat3 plane_block(const Mat6& C) {
  Mat3 P;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) P(a, b) = C(kPlaneVoigt[a], kPlaneVoigt[b]);
  return P;
}

Mat6 isotropic_tensor(double E, double nu) {
  const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), mu = E / (2 * (1 + nu));
  Mat6 C = Mat6::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) C(i, j) = lambda;
    C(i, i) = lambda + 2 * mu;
    C(3 + i, 3 + i) = mu;
  }
  return C;
}

Mat6 cubic_tensor(double C11, double C12, double C44) {
  Mat6 C = Mat6::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) C(i, j) = C12;
    C(i, i) = C11;
    C(3 + i, 3 + i) = C44;
  }
  return C;
}

CubicModuli cubic_moduli(const Mat6& C) {
  CubicModuli m;
  m.C11 = (C(0, 0) + C(1, 1) + C(2, 2)) / 3;
  m.C12 = (C(0, 1) + C(0, 2) + C(1, 2)) / 3;
  m.C44 = (C(3, 3) + C(4, 4) + C(5, 5)) / 3;
  m.E = (m.C11 - m.C12) * (m.C11 + 2 * m.C12) / (m.C11 + m.C12);
  m.nu = m.C12 / (m.C11 + m.C12);
  m.G = m.C44;
  m.shear_ratio = 2 * m.G * (1 + m.nu) / m.E;
  return m;
}

double cubic_deviation(const Mat6& C) {
  const CubicModuli m = cubic_moduli(C);
  return (C - cubic_tensor(m.C11, m.C12, m.C44)).cwiseAbs().maxCoeff() / std::abs(m.C11);
}

Mat6 to_material_voigt_order(const Mat6& C) {
  // Material index i holds homogenization index from[i]: xy <- 5, yz <- 3, zx <- 4.
  static constexpr int from[6] = {0, 1, 2, 5, 3, 4};
  Mat6 out;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) out(i, j) = C(from[i], from[j]);
  return out;
}

}  // namespace msfab
