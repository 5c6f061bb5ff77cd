#pragma once
// Anisotropic small-strain elasticity with a 6x6 Voigt stiffness (thesis Eq. 2.5):
//   e = strain_to_voigt((F + F^T)/2 - I)  (order xx,yy,zz,xy,yz,zx; engineering shears)
//   Psi = 1/2 e^T C e,  sigma_voigt = C e,  P = voigt_to_stress(C e) (symmetric),
//   dP/dF = B^T C B with B = voigt_strain_operator(), constant.
// shear_modulus()/lame_lambda() are those of the isotropic projection of C.
#include "material/stiffness_material.hpp"

namespace msfab {

class LinearAnisotropic final : public StiffnessMaterial {
 public:
  // Throws InputError unless C is finite, symmetric and positive definite.
  explicit LinearAnisotropic(const Mat6& C);

  void evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const override;
  std::string name() const override { return "linear_anisotropic"; }
  bool frame_indifferent() const override { return false; }

 private:
  Mat9 dPdF_;
};

}  // namespace msfab
