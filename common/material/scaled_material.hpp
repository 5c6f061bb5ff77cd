#pragma once
// A material whose energy is a fixed multiple of another's. The Rayleigh
// stiffness-damping matrix b K(q) of a multi-material body is the Hessian of
// the same mesh with every material scaled by its own b, and the tangent
// options below say which part of K(q) a damping matrix may use.
#include <Eigen/Eigenvalues>

#include "material/material.hpp"

namespace msfab {

enum class ScaledTangent {
  // dP/dF as it is.
  full,
  // dP/dF clamped to its positive semidefinite part at every point, so a
  // damping matrix built from it never does positive work: a compressed or
  // buckling Neo-Hookean body has an indefinite K(q), and b K(q) would then
  // pump energy into those modes.
  psd,
  // The material part only: dP/dF less the geometric term dF -> dF S
  // (S = F^-1 P, the second Piola-Kirchhoff stress), then clamped as `psd`.
  // What remains is dF -> F C sym(F^T dF), which vanishes on every rigid
  // velocity dF = W F (W skew) at any deformation. b K(q) itself does not:
  // K(q) W F = W P, so a stressed body that spins (a jumper whose flexure
  // still rings in flight) is braked by its own damping and loses angular
  // momentum no force outside it took away (docs/dynamics.md, "Damping that
  // spares rigid motion"). At rest S = 0 and the two agree. A material that
  // is not frame-indifferent (small-strain linear) has no such split and
  // gets `psd`.
  material_psd,
};

class ScaledMaterial final : public Material {
 public:
  ScaledMaterial(MaterialPtr base, double factor, ScaledTangent tangent = ScaledTangent::full)
      : base_(std::move(base)), factor_(factor), tangent_(tangent) {}
  void evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const override {
    Mat3 stress;
    Mat3* P_out = P ? P : (dPdF && tangent_ == ScaledTangent::material_psd ? &stress : nullptr);
    base_->evaluate(F, psi, P_out, dPdF);
    if (psi) *psi *= factor_;
    if (P_out) *P_out *= factor_;
    if (!dPdF) return;
    *dPdF *= factor_;
    if (tangent_ == ScaledTangent::full) return;
    const bool material_part = tangent_ == ScaledTangent::material_psd && base_->frame_indifferent();
    if (material_part) {
      // Column-major flattening (core/types.hpp): (dF S)(i, j) = sum_k dF(i, k) S(k, j).
      const Mat3 S = F.inverse() * *P_out;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          for (int k = 0; k < 3; ++k) (*dPdF)(i + 3 * j, i + 3 * k) -= S(k, j);
    }
    const Eigen::SelfAdjointEigenSolver<Mat9> eig(0.5 * (*dPdF + dPdF->transpose()));
    if (eig.eigenvalues().minCoeff() < 0)
      *dPdF = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
    else if (material_part)
      *dPdF = 0.5 * (*dPdF + dPdF->transpose());
  }
  double shear_modulus() const override { return factor_ * base_->shear_modulus(); }
  double lame_lambda() const override { return factor_ * base_->lame_lambda(); }
  std::string name() const override { return "scaled_" + base_->name(); }
  bool frame_indifferent() const override { return base_->frame_indifferent(); }

 private:
  MaterialPtr base_;
  double factor_;
  ScaledTangent tangent_;
};

}  // namespace msfab
