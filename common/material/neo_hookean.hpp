#pragma once
// Compressible Neo-Hookean elasticity (thesis §2.1.3), J = det F:
//   Psi = mu/2 (tr(F^T F) - 3) - mu log J + lambda/2 (log J)^2
//   P   = mu (F - F^-T) + lambda log J F^-T
//   dP  = mu dF + (mu - lambda log J) F^-T dF^T F^-T + lambda tr(F^-1 dF) F^-T
// For J <= 0 (inverted) Psi = +inf and P, dP/dF are zero, never NaN.
#include "material/material.hpp"

namespace msfab {

class NeoHookean final : public Material {
 public:
  // Throws InputError unless E > 0 is finite and -1 < nu < 0.5.
  NeoHookean(double E, double nu);
  // From Lame parameters, as fitted coarse materials are: accepts any finite
  // mu >= 0, lambda >= 0 (mu = 0 is allowed: a fitted quadrature point may
  // keep only its volumetric term). Throws InputError otherwise.
  static std::shared_ptr<const NeoHookean> from_lame(double mu, double lambda);

  void evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const override;
  double shear_modulus() const override { return mu_; }
  double lame_lambda() const override { return lambda_; }
  std::string name() const override { return "neo_hookean"; }

  double youngs_modulus() const { return E_; }
  double poisson_ratio() const { return nu_; }

 private:
  struct LameTag {};
  NeoHookean(LameTag, double mu, double lambda);

  double E_, nu_, mu_, lambda_;
};

}  // namespace msfab
