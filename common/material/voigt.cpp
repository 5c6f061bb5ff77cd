#include "material/voigt.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <sstream>

#include "core/errors.hpp"
#include "material/material.hpp"

namespace msfab {

namespace {

// Tensor indices of the shear in Voigt slot 3 + s: xy, yz, zx.
constexpr int kShearI[3] = {0, 1, 2};
constexpr int kShearJ[3] = {1, 2, 0};

std::string num(double v) {
  std::ostringstream os;
  os.precision(10);
  os << v;
  return os.str();
}

}  // namespace

Vec6 strain_to_voigt(const Mat3& eps) {
  Vec6 e;
  e << eps(0, 0), eps(1, 1), eps(2, 2), eps(0, 1) + eps(1, 0), eps(1, 2) + eps(2, 1), eps(2, 0) + eps(0, 2);
  return e;
}

Mat3 voigt_to_strain(const Vec6& e) {
  Mat3 eps;
  eps << e(0), 0.5 * e(3), 0.5 * e(5),  //
      0.5 * e(3), e(1), 0.5 * e(4),     //
      0.5 * e(5), 0.5 * e(4), e(2);
  return eps;
}

Vec6 stress_to_voigt(const Mat3& sigma) {
  Vec6 s;
  s << sigma(0, 0), sigma(1, 1), sigma(2, 2), 0.5 * (sigma(0, 1) + sigma(1, 0)), 0.5 * (sigma(1, 2) + sigma(2, 1)),
      0.5 * (sigma(2, 0) + sigma(0, 2));
  return s;
}

Mat3 voigt_to_stress(const Vec6& s) {
  Mat3 sigma;
  sigma << s(0), s(3), s(5),  //
      s(3), s(1), s(4),       //
      s(5), s(4), s(2);
  return sigma;
}

Eigen::Matrix<double, 6, 9> voigt_strain_operator() {
  Eigen::Matrix<double, 6, 9> B = Eigen::Matrix<double, 6, 9>::Zero();
  for (int i = 0; i < 3; ++i) B(i, i + 3 * i) = 1.0;
  for (int s = 0; s < 3; ++s) {
    const int i = kShearI[s], j = kShearJ[s];
    B(3 + s, i + 3 * j) = 1.0;
    B(3 + s, j + 3 * i) = 1.0;
  }
  return B;
}

void check_elastic_constants(double E, double nu) {
  if (!std::isfinite(E) || E <= 0.0) throw InputError("Young's modulus E must be positive and finite, got " + num(E));
  if (!std::isfinite(nu) || nu <= -1.0 || nu >= 0.5)
    throw InputError("Poisson's ratio nu must lie in (-1, 0.5), got " + num(nu));
}

Mat6 cubic_C(double E, double nu, double G) {
  check_elastic_constants(E, nu);
  if (!std::isfinite(G) || G <= 0.0) throw InputError("shear modulus G must be positive and finite, got " + num(G));
  const double Ehat = E / ((1.0 - 2.0 * nu) * (1.0 + nu));
  Mat6 C = Mat6::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) C(i, j) = (i == j ? (1.0 - nu) : nu) * Ehat;
    C(3 + i, 3 + i) = G;
  }
  return C;
}

Mat6 isotropic_C(double E, double nu) {
  check_elastic_constants(E, nu);
  return cubic_C(E, nu, lame_mu(E, nu));
}

Mat6 lame_C(double mu, double lambda) {
  Mat6 C = Mat6::Zero();
  C.topLeftCorner<3, 3>().setConstant(lambda);
  C.topLeftCorner<3, 3>().diagonal().array() += 2 * mu;
  C.bottomRightCorner<3, 3>().diagonal().setConstant(mu);
  return C;
}

Mat6 orthotropic_C(const OrthotropicConstants& k) {
  const double moduli[6] = {k.Ex, k.Ey, k.Ez, k.Gxy, k.Gyz, k.Gzx};
  const char* names[6] = {"Ex", "Ey", "Ez", "Gxy", "Gyz", "Gzx"};
  for (int i = 0; i < 6; ++i)
    if (!std::isfinite(moduli[i]) || moduli[i] <= 0.0)
      throw InputError(std::string("orthotropic modulus ") + names[i] + " must be positive and finite, got " +
                       num(moduli[i]));
  const double ratios[3] = {k.nu_xy, k.nu_yz, k.nu_zx};
  const char* ratio_names[3] = {"nu_xy", "nu_yz", "nu_zx"};
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(ratios[i]))
      throw InputError(std::string("orthotropic Poisson's ratio ") + ratio_names[i] + " must be finite, got " +
                       num(ratios[i]));
  Mat6 S = Mat6::Zero();
  S(0, 0) = 1.0 / k.Ex;
  S(1, 1) = 1.0 / k.Ey;
  S(2, 2) = 1.0 / k.Ez;
  S(0, 1) = S(1, 0) = -k.nu_xy / k.Ex;
  S(1, 2) = S(2, 1) = -k.nu_yz / k.Ey;
  S(0, 2) = S(2, 0) = -k.nu_zx / k.Ez;
  S(3, 3) = 1.0 / k.Gxy;
  S(4, 4) = 1.0 / k.Gyz;
  S(5, 5) = 1.0 / k.Gzx;
  // A compliance that is not positive definite has no physical inverse; the
  // check on C below would catch it too, but this message names the cause.
  const Mat3 S_normal = S.topLeftCorner<3, 3>();
  if (!(S_normal.ldlt().vectorD().minCoeff() > 0.0))
    throw InputError("orthotropic Poisson's ratios (nu_xy=" + num(k.nu_xy) + ", nu_yz=" + num(k.nu_yz) +
                     ", nu_zx=" + num(k.nu_zx) + ") give a compliance that is not positive definite");
  Mat6 C = S.ldlt().solve(Mat6::Identity());
  C = 0.5 * (C + C.transpose());
  check_stiffness(C, "orthotropic stiffness");
  return C;
}

void check_stiffness(const Mat6& C, const std::string& what) {
  if (!C.allFinite()) throw InputError(what + " has a non-finite entry");
  const double scale = C.cwiseAbs().maxCoeff();
  const double asym = (C - C.transpose()).cwiseAbs().maxCoeff();
  if (asym > 1e-10 * scale) throw InputError(what + " is not symmetric (largest |C_ij - C_ji| = " + num(asym) + ")");
  // Pivoted LDL^T: C is positive definite iff every pivot is positive.
  const Mat6 sym = 0.5 * (C + C.transpose());
  const double lo = sym.ldlt().vectorD().minCoeff();
  if (!(lo > 1e-12 * scale))
    throw InputError(what + " is not positive definite (smallest LDL^T pivot " + num(lo) + ")");
}

void isotropic_projection(const Mat6& C, double* mu, double* lambda) {
  const double iijj = C.topLeftCorner<3, 3>().sum();
  const double ijij = C.topLeftCorner<3, 3>().trace() + 2.0 * C.bottomRightCorner<3, 3>().trace();
  const double K = iijj / 9.0;
  const double m = (ijij - 3.0 * K) / 10.0;
  if (mu) *mu = m;
  if (lambda) *lambda = K - 2.0 * m / 3.0;
}

}  // namespace msfab
