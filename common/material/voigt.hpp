#pragma once
// Voigt notation for symmetric 3x3 tensors and 6x6 stiffness matrices.
//
// Order (thesis §2.1.3): xx, yy, zz, xy, yz, zx.
// Strains use ENGINEERING shears (gamma_xy = 2 eps_xy), stresses use tensor
// components, so sigma_voigt = C e, the energy is 1/2 e^T C e, and the
// shear diagonal C(3,3), C(4,4), C(5,5) are shear moduli (C_1212, C_2323, C_1313).
#include <Eigen/Core>
#include <string>

#include "core/types.hpp"

namespace msfab {

// Strain tensor -> (exx, eyy, ezz, 2exy, 2eyz, 2ezx). For a non-symmetric input
// the shears are eps_ij + eps_ji, i.e. those of its symmetric part.
Vec6 strain_to_voigt(const Mat3& eps);
// Inverse of strain_to_voigt for symmetric tensors (halves the shears).
Mat3 voigt_to_strain(const Vec6& e);
// Stress tensor -> (sxx, syy, szz, sxy, syz, szx), off-diagonals of the symmetric part.
Vec6 stress_to_voigt(const Mat3& sigma);
// (sxx, syy, szz, sxy, syz, szx) -> symmetric stress tensor.
Mat3 voigt_to_stress(const Vec6& s);

// The 6x9 matrix B with strain_to_voigt(dF) = B * flat(dF) for any dF (the
// column-major flattening of core/types.hpp). A stiffness C then acts on
// displacement gradients as B^T C B.
Eigen::Matrix<double, 6, 9> voigt_strain_operator();

// Throws InputError unless E > 0 is finite and -1 < nu < 0.5 (the range where
// the isotropic stiffness is positive definite).
void check_elastic_constants(double E, double nu);

// Stiffness with cubic symmetry as in the thesis: C11 = (1-nu) Ehat,
// C12 = nu Ehat, C44 = G, Ehat = E / ((1 - 2nu)(1 + nu)). Validates E, nu, G.
Mat6 cubic_C(double E, double nu, double G);
// Isotropic stiffness: cubic_C(E, nu, E / (2 (1 + nu))).
Mat6 isotropic_C(double E, double nu);
// Isotropic stiffness from the Lame parameters (no validation: a part of a
// split may have lambda = 0 or mu = 0).
Mat6 lame_C(double mu, double lambda);

// Orthotropic stiffness from engineering constants, as the inverse of the
// compliance S with S11 = 1/Ex, S12 = -nu_xy/Ex, S23 = -nu_yz/Ey,
// S13 = -nu_zx/Ez, S44 = 1/Gxy, S55 = 1/Gyz, S66 = 1/Gzx
// (nu_ij: lateral contraction along j under uniaxial stress along i).
struct OrthotropicConstants {
  double Ex, Ey, Ez;
  double nu_xy, nu_yz, nu_zx;
  double Gxy, Gyz, Gzx;
};
Mat6 orthotropic_C(const OrthotropicConstants& k);

// Throws InputError unless C is finite, symmetric (to a relative 1e-10) and
// positive definite. `what` names the quantity in the message.
void check_stiffness(const Mat6& C, const std::string& what = "stiffness matrix C");

// Lame parameters (mu, lambda) of the isotropic projection of a Voigt stiffness:
// K = C_iijj / 9, mu = (C_ijij - 3 K) / 10, lambda = K - 2 mu / 3.
void isotropic_projection(const Mat6& C, double* mu, double* lambda);

}  // namespace msfab
