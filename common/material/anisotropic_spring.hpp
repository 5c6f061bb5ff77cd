#pragma once
// The anisotropic term of the coarse material model (thesis Eq. 2.7):
//   Psi = C (l - 1)^2,  l = ||F v||,  v a unit direction,
//   P   = 2C (1 - 1/l) (F v) v^T,
//   dP  = 2C [ (1 - 1/l) dF v v^T + (1/l^3) (F v)(F v)^T dF v v^T ].
// (The thesis prints the gradient of (l - 1)^2 without the factor C of the
// energy; here P is the exact derivative of Psi.)
// It is a pure correction term: shear_modulus() and lame_lambda() return 0,
// so scaling heuristics see only the isotropic materials it is added to.
// When l < kMinStretch the direction of F v is undefined; P is then zero and
// dP/dF keeps only its regular part 2C dF v v^T, so results stay finite.
#include "material/material.hpp"

namespace msfab {

class AnisotropicSpring final : public Material {
 public:
  static constexpr double kMinStretch = 1e-8;

  // Throws InputError unless C >= 0 is finite and v is finite and nonzero
  // (v is normalized here).
  AnisotropicSpring(double C, const Vec3& v);

  void evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const override;
  double shear_modulus() const override { return 0.0; }
  double lame_lambda() const override { return 0.0; }
  std::string name() const override { return "anisotropic_spring"; }

  double stiffness() const { return C_; }
  const Vec3& direction() const { return v_; }

 private:
  double C_;
  Vec3 v_;
};

}  // namespace msfab
