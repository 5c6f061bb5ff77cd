#pragma once
// Hyperelastic energy density Psi(F) with its first Piola-Kirchhoff stress
// P = dPsi/dF and the stress derivative dP/dF (a 9x9 matrix in the flattening
// of core/types.hpp). Every material in the toolkit implements this.
#include <limits>
#include <memory>
#include <string>

#include "core/types.hpp"

namespace msfab {

class Material {
 public:
  virtual ~Material() = default;

  // Evaluates any subset of (energy density, P, dP/dF); pass nullptr to skip.
  // A state the model cannot represent (det F <= 0 for Neo-Hookean) gives
  // psi = +infinity so line searches back off; P and dPdF are then left
  // finite but meaningless, and callers must not use them.
  virtual void evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const = 0;

  // Small-strain (linearized at F = I) Lame parameters, used for scaling
  // (load magnitudes, regularization). Anisotropic models return the
  // isotropic part of their stiffness.
  virtual double shear_modulus() const = 0;
  virtual double lame_lambda() const = 0;

  virtual std::string name() const = 0;

  // Psi(R F) = Psi(F) for every rotation R. Then dP/dF applied to a rigid
  // velocity W F (W skew) gives W P, so its geometric part is what makes a
  // stressed body's stiffness see rotation (material/scaled_material.hpp).
  // Small-strain models, whose energy grows under rotation, say false.
  virtual bool frame_indifferent() const { return true; }

  double energy(const Mat3& F) const {
    double e = 0;
    evaluate(F, &e, nullptr, nullptr);
    return e;
  }
  Mat3 stress(const Mat3& F) const {
    Mat3 P;
    evaluate(F, nullptr, &P, nullptr);
    return P;
  }
  Mat9 stress_derivative(const Mat3& F) const {
    Mat9 H;
    evaluate(F, nullptr, nullptr, &H);
    return H;
  }
};

using MaterialPtr = std::shared_ptr<const Material>;

constexpr double kInfiniteEnergy = std::numeric_limits<double>::infinity();

// Conversions between engineering constants and Lame parameters.
inline double lame_mu(double E, double nu) { return E / (2.0 * (1.0 + nu)); }
inline double lame_lambda(double E, double nu) { return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)); }

}  // namespace msfab
