#pragma once
// A material whose energy is a fixed multiple of another's. The Rayleigh
// stiffness-damping matrix b K(q) of a multi-material body is the Hessian of
// the same mesh with every material scaled by its own b.
#include "material/material.hpp"

namespace msfab {

class ScaledMaterial final : public Material {
 public:
  ScaledMaterial(MaterialPtr base, double factor) : base_(std::move(base)), factor_(factor) {}
  void evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const override {
    base_->evaluate(F, psi, P, dPdF);
    if (psi) *psi *= factor_;
    if (P) *P *= factor_;
    if (dPdF) *dPdF *= factor_;
  }
  double shear_modulus() const override { return factor_ * base_->shear_modulus(); }
  double lame_lambda() const override { return factor_ * base_->lame_lambda(); }
  std::string name() const override { return "scaled_" + base_->name(); }

 private:
  MaterialPtr base_;
  double factor_;
};

}  // namespace msfab
