#pragma once
// Anisotropic St. Venant-Kirchhoff: the small-strain stiffness C acting on
// the Green strain, so that it is invariant under rotations:
//   E = (F^T F - I) / 2,  e = strain_to_voigt(E),  Psi = 1/2 e^T C e,
//   S = voigt_to_stress(C e),  P = F S.
// At F = I it linearizes to C exactly. C may be positive semidefinite: the
// model is meant as the anisotropic part beside an isotropic Neo-Hookean
// one (MaterialSum), which keeps the sum stable under large compression,
// where St. Venant-Kirchhoff alone softens.
#include "material/stiffness_material.hpp"

namespace msfab {

class GreenAnisotropic final : public StiffnessMaterial {
 public:
  // Throws InputError unless C is finite, symmetric and positive semidefinite.
  explicit GreenAnisotropic(const Mat6& C);

  void evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const override;
  std::string name() const override { return "green_anisotropic"; }
};

}  // namespace msfab
