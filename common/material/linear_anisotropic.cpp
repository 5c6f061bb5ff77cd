#include "material/linear_anisotropic.hpp"

#include "material/voigt.hpp"

namespace msfab {

namespace {
const Mat6& checked(const Mat6& C) {
  check_stiffness(C);
  return C;
}
}  // namespace

LinearAnisotropic::LinearAnisotropic(const Mat6& C) : StiffnessMaterial(checked(C)) {
  const Eigen::Matrix<double, 6, 9> B = voigt_strain_operator();
  dPdF_ = B.transpose() * C_ * B;
}

void LinearAnisotropic::evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const {
  const Vec6 e = strain_to_voigt(F - Mat3::Identity());
  const Vec6 s = C_ * e;
  if (psi) *psi = 0.5 * e.dot(s);
  if (P) *P = voigt_to_stress(s);
  if (dPdF) *dPdF = dPdF_;
}

}  // namespace msfab
