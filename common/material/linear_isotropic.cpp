#include "material/linear_isotropic.hpp"

#include "material/voigt.hpp"

namespace msfab {

LinearIsotropic::LinearIsotropic(double E, double nu) : E_(E), nu_(nu) {
  check_elastic_constants(E, nu);
  mu_ = lame_mu(E, nu);
  lambda_ = msfab::lame_lambda(E, nu);
  // H(i+3j, k+3l) = mu (d_ik d_jl + d_il d_jk) + lambda d_ij d_kl
  dPdF_.setZero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      dPdF_(i + 3 * j, i + 3 * j) += mu_;
      dPdF_(i + 3 * j, j + 3 * i) += mu_;
      dPdF_(i + 3 * i, j + 3 * j) += lambda_;
    }
}

void LinearIsotropic::evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const {
  const Mat3 eps = 0.5 * (F + F.transpose()) - Mat3::Identity();
  const double tr = eps.trace();
  if (psi) *psi = mu_ * eps.squaredNorm() + 0.5 * lambda_ * tr * tr;
  if (P) *P = 2.0 * mu_ * eps + lambda_ * tr * Mat3::Identity();
  if (dPdF) *dPdF = dPdF_;
}

}  // namespace msfab
