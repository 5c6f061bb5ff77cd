#pragma once
// 6 x 6 elasticity tensors in Voigt notation (docs/homogenization.md):
// order xx, yy, zz, yz, xz, xy, engineering shear strains (gamma = 2 eps),
// so sigma = C eps and the energy density is eps^T C eps / 2.
#include "core/types.hpp"

namespace msfab {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

// The strain tensor of a Voigt strain vector (shear halved).
Mat3 strain_tensor(const Vec6& voigt);

// The same tensor in the shear order of material/voigt.hpp (xx, yy, zz, xy,
// yz, zx), which the constitutive models (LinearAnisotropic,
// GreenAnisotropic) take.
Mat6 to_material_voigt_order(const Mat6& C);

// Isotropic tensor from Young's modulus and Poisson's ratio.
Mat6 isotropic_tensor(double E, double nu);

// Voigt rows of the in-plane components (xx, yy, xy) of a 2D
// (plane-strain) cell, and that 3 x 3 block of a 6 x 6 tensor.
inline constexpr int kPlaneVoigt[3] = {0, 1, 5};
Mat3 plane_block(const Mat6& C);

// Moduli of a tensor with cubic symmetry (axes along x, y, z): C11, C12,
// C44 averaged over their three copies, and the engineering constants
// E = (C11 - C12)(C11 + 2 C12) / (C11 + C12), nu = C12 / (C11 + C12),
// G = C44, and the shear-modulus ratio G' = 2 G (1 + nu) / E (1 for an
// isotropic tensor; thesis §3.3.2).
struct CubicModuli {
  double C11 = 0, C12 = 0, C44 = 0;
  double E = 0, nu = 0, G = 0, shear_ratio = 0;
};
CubicModuli cubic_moduli(const Mat6& C);
// The cubic tensor (axes along x, y, z) with these three moduli.
Mat6 cubic_tensor(double C11, double C12, double C44);

// Largest deviation of C from the cubic tensor of cubic_moduli(C), relative
// to C11: 0 for an exactly cubic tensor.
double cubic_deviation(const Mat6& C);

}  // namespace msfab
