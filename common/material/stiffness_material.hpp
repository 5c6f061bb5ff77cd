#pragma once
// A material defined by a 6x6 Voigt stiffness C (the small-strain one, or the
// one acting on the Green strain). Its isotropic projection gives the shear
// modulus and Lame lambda that element-level heuristics ask every material for.
#include "material/material.hpp"
#include "material/voigt.hpp"

namespace msfab {

class StiffnessMaterial : public Material {
 public:
  double shear_modulus() const override { return mu_; }
  double lame_lambda() const override { return lambda_; }
  const Mat6& stiffness() const { return C_; }

 protected:
  // C must have been checked by the derived class; it is symmetrized here.
  explicit StiffnessMaterial(const Mat6& C) : C_(0.5 * (C + C.transpose())) {
    isotropic_projection(C_, &mu_, &lambda_);
  }

  Mat6 C_;
  double mu_ = 0, lambda_ = 0;
};

}  // namespace msfab
