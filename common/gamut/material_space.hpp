#pragma once
// The material property spaces of the gamut (thesis §3.2.3, Fig. 3-14) and
// their normalization to the unit cube that the level set lives in.
//
//   3D cubic:        (E, nu, G, rho)          from a cubic C^H
//   2D cubic:        (E, nu, G, rho)          from a square-symmetric plane-strain C
//   2D orthotropic:  (Ex, Ey, nu_xy, G, rho)  from an orthotropic plane-strain C
//
// rho is the volume fraction of the stiffest base material. Moduli are
// normalized on a log scale over `decades` decades below the stiffest base
// material's E (they span orders of magnitude, §3.2.3); Poisson's ratios
// linearly over [-1, 0.5] in 3D and [-1, 1] in 2D (plane strain allows
// nu_xy up to 1); rho over [0, 1].
#include <string>
#include <vector>

#include "core/types.hpp"
#include "homog/elastic_tensor.hpp"

namespace msfab {

enum class MaterialSpaceKind { cubic3d, cubic2d, orthotropic2d };

class MaterialSpace {
 public:
  // InputError for E_stiff <= 0 or decades <= 0.
  MaterialSpace(MaterialSpaceKind kind, double E_stiff, double decades = 4.0);
  // "cubic3d" | "cubic2d" | "orthotropic2d"; InputError naming the choices.
  static MaterialSpaceKind parse_kind(const std::string& name);

  MaterialSpaceKind kind() const { return kind_; }
  double E_stiff() const { return E_stiff_; }  // the modulus that normalizes to 1
  int dimension() const;
  std::vector<std::string> names() const;

  // Raw properties of a homogenized tensor (6 x 6 in 3D; the 3 x 3 plane
  // block in 2D) and its stiff-material fraction.
  VecX properties(const Mat6& C, double rho) const;
  VecX properties_2d(const Mat3& C, double rho) const;
  // Either of the above for the full 3D tensor of a homogenized cell: a 2D
  // space reads the in-plane block (xx, yy, xy) of a plane-strain cell.
  VecX cell_properties(const Mat6& C, double rho) const;
  // The raw properties of a 6 x 6 (3D) or 3 x 3 plane-block (2D) tensor,
  // as above, with d property_i / dC (entries treated as independent; the
  // same size as C) in `dC` when non-null. The last entry, rho, has a zero
  // derivative.
  VecX properties_with_gradient(const MatX& C, double rho, std::vector<MatX>* dC) const;
  // d unit_i / d raw_i at raw properties `raw` (normalize() acts per coordinate).
  VecX unit_derivative(const VecX& raw) const;
  // The tensor with given raw properties (the inverse of the above, used by
  // the topology optimizer): 6 x 6 cubic, or 3 x 3 plane strain.
  Mat6 tensor_3d(const VecX& raw) const;
  Mat3 tensor_2d(const VecX& raw) const;

  // Raw <-> unit cube. normalize() does not clamp: values outside [0, 1]
  // mean the property lies outside the space's box.
  VecX normalize(const VecX& raw) const;
  VecX denormalize(const VecX& unit) const;
  // Clamps unit coordinates into [0, 1]; false if one lay outside by more
  // than round-off (1e-9: the solid cell sits exactly on the box's faces).
  static bool clamp_to_box(VecX& unit);
  // Whether property `coordinate` is a modulus (log-normalized: E, Ex, Ey, G).
  bool is_modulus(int coordinate) const;

 private:
  MaterialSpaceKind kind_;
  double E_stiff_, decades_;
  double nu_low() const { return -1.0; }
  double nu_high() const { return kind_ == MaterialSpaceKind::cubic3d ? 0.5 : 1.0; }
  // x with each coordinate mapped by its kind: the last (density) by
  // `density`, moduli by `modulus`, Poisson ratios by `poisson`.
  template <class Density, class Modulus, class Poisson>
  VecX map_coordinates(const VecX& x, const char* what, Density density, Modulus modulus, Poisson poisson) const;
};

}  // namespace msfab
