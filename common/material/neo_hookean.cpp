#include "material/neo_hookean.hpp"

#include <cmath>
#include <sstream>

#include "core/errors.hpp"
#include "material/voigt.hpp"

namespace msfab {

NeoHookean::NeoHookean(double E, double nu) : E_(E), nu_(nu) {
  check_elastic_constants(E, nu);
  mu_ = lame_mu(E, nu);
  lambda_ = msfab::lame_lambda(E, nu);
}

NeoHookean::NeoHookean(LameTag, double mu, double lambda) : mu_(mu), lambda_(lambda) {
  if (!std::isfinite(mu) || !std::isfinite(lambda) || mu < 0.0 || lambda < 0.0) {
    std::ostringstream os;
    os.precision(10);
    os << "Neo-Hookean Lame parameters must be finite and >= 0, got mu = " << mu << ", lambda = " << lambda;
    throw InputError(os.str());
  }
  // Engineering constants for reporting only; mu = 0 gives E = 0.
  E_ = (mu + lambda > 0.0) ? mu * (3.0 * lambda + 2.0 * mu) / (lambda + mu) : 0.0;
  nu_ = (mu + lambda > 0.0) ? lambda / (2.0 * (lambda + mu)) : 0.0;
}

std::shared_ptr<const NeoHookean> NeoHookean::from_lame(double mu, double lambda) {
  return std::shared_ptr<const NeoHookean>(new NeoHookean(LameTag{}, mu, lambda));
}

void NeoHookean::evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const {
  // Cofactor matrix: F^-T = cof(F) / J, with J = row 0 of F . row 0 of cof(F).
  Mat3 cof;
  cof(0, 0) = F(1, 1) * F(2, 2) - F(1, 2) * F(2, 1);
  cof(0, 1) = F(1, 2) * F(2, 0) - F(1, 0) * F(2, 2);
  cof(0, 2) = F(1, 0) * F(2, 1) - F(1, 1) * F(2, 0);
  cof(1, 0) = F(0, 2) * F(2, 1) - F(0, 1) * F(2, 2);
  cof(1, 1) = F(0, 0) * F(2, 2) - F(0, 2) * F(2, 0);
  cof(1, 2) = F(0, 1) * F(2, 0) - F(0, 0) * F(2, 1);
  cof(2, 0) = F(0, 1) * F(1, 2) - F(0, 2) * F(1, 1);
  cof(2, 1) = F(0, 2) * F(1, 0) - F(0, 0) * F(1, 2);
  cof(2, 2) = F(0, 0) * F(1, 1) - F(0, 1) * F(1, 0);
  const double J = F(0, 0) * cof(0, 0) + F(0, 1) * cof(0, 1) + F(0, 2) * cof(0, 2);

  // `!(J > 0)` also catches a NaN determinant.
  if (!(J > 0.0) || !std::isfinite(J)) {
    if (psi) *psi = kInfiniteEnergy;
    if (P) P->setZero();
    if (dPdF) dPdF->setZero();
    return;
  }

  const Mat3 FinvT = cof / J;
  const double logJ = std::log(J);
  if (psi) *psi = 0.5 * mu_ * (F.squaredNorm() - 3.0) - mu_ * logJ + 0.5 * lambda_ * logJ * logJ;
  if (P) *P = mu_ * (F - FinvT) + (lambda_ * logJ) * FinvT;
  if (dPdF) {
    // With G = F^-T: d(G dF^T G)_ij / dF_kl = G_il G_kj, and
    // tr(F^-1 dF) = G : dF, so the last term is lambda vec(G) vec(G)^T.
    const double c = mu_ - lambda_ * logJ;
    Mat9& H = *dPdF;
    for (int l = 0; l < 3; ++l)
      for (int k = 0; k < 3; ++k) {
        const int b = k + 3 * l;
        const double gkl = lambda_ * FinvT(k, l);
        for (int j = 0; j < 3; ++j) {
          const double ckj = c * FinvT(k, j);
          for (int i = 0; i < 3; ++i) H(i + 3 * j, b) = ckj * FinvT(i, l) + gkl * FinvT(i, j);
        }
        H(b, b) += mu_;
      }
  }
}

}  // namespace msfab
