#pragma once
// A material whose energy density is the sum of several materials' densities,
// e.g. Neo-Hookean plus the anisotropic spring at one quadrature point of the
// coarse model (thesis Eq. 2.7). Energy, stress, stress derivative and the
// Lame parameters all add; an infinite term makes the sum infinite.
#include <vector>

#include "material/material.hpp"

namespace msfab {

class MaterialSum final : public Material {
 public:
  // Throws InputError if `terms` is empty or holds a null pointer.
  explicit MaterialSum(std::vector<MaterialPtr> terms);

  void evaluate(const Mat3& F, double* psi, Mat3* P, Mat9* dPdF) const override;
  double shear_modulus() const override;
  double lame_lambda() const override;
  // "sum(a+b+...)" of the terms' names.
  std::string name() const override;
  bool frame_indifferent() const override;

  const std::vector<MaterialPtr>& terms() const { return terms_; }

 private:
  std::vector<MaterialPtr> terms_;
};

}  // namespace msfab
