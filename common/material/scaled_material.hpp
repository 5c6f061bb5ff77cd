#pragma once
// A material whose energy is a fixed multiple of another's. The Rayleigh
// stiffness-damping matrix b K(q) of a multi-material body is the Hessian of
// the same mesh with every material scaled by its own b. With
// `project_psd`, dP/dF is clamped to its positive semidefinite part at
// every point, so a damping matrix built from it never does positive work:
// a compressed or buckling Neo-Hookean body has an indefinite K(q), and
// b K(q) would then pump energy into those modes.
#include <Eigen/Eigenvalues>

#include "material/material.hpp"

namespace msfab {

class ScaledMaterial final : public Material {
 public:
  ScaledMaterial(MaterialPtr base, double factor, bool project_psd = false)
      : base_(std::move(base)), factor_(factor), project_psd_(project_psd) {}
  void evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const override {
    base_->evaluate(F, psi, P, dPdF);
    if (psi) *psi *= factor_;
    if (P) *P *= factor_;
    if (dPdF) {
      *dPdF *= factor_;
      if (project_psd_) {
        const Eigen::SelfAdjointEigenSolver<Mat9> eig(0.5 * (*dPdF + dPdF->transpose()));
        if (eig.eigenvalues().minCoeff() < 0)
          *dPdF = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
      }
    }
  }
  double shear_modulus() const override { return factor_ * base_->shear_modulus(); }
  double lame_lambda() const override { return factor_ * base_->lame_lambda(); }
  std::string name() const override { return "scaled_" + base_->name(); }

 private:
  MaterialPtr base_;
  double factor_;
  bool project_psd_;
};

}  // namespace msfab
