#pragma once
// Isotropic small-strain elasticity (thesis §2.1.3):
//   eps = (F + F^T)/2 - I,  Psi = mu eps:eps + lambda/2 tr(eps)^2,
//   P = mu (F + F^T - 2I) + lambda tr(F - I) I,  dP/dF constant.
// Not rotation invariant: use for small deformations only.
#include "material/material.hpp"

namespace msfab {

class LinearIsotropic final : public Material {
 public:
  // Throws InputError unless E > 0 is finite and -1 < nu < 0.5.
  LinearIsotropic(double E, double nu);

  void evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const override;
  double shear_modulus() const override { return mu_; }
  double lame_lambda() const override { return lambda_; }
  std::string name() const override { return "linear_isotropic"; }
  bool frame_indifferent() const override { return false; }

  double youngs_modulus() const { return E_; }
  double poisson_ratio() const { return nu_; }

 private:
  double E_, nu_, mu_, lambda_;
  Mat9 dPdF_;  // constant, built once
};

}  // namespace msfab
