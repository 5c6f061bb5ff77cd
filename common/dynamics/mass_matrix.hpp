#pragma once
// Stiffness-consistent mass matrix (thesis App. B.4): per element
//   M_e = rho_e \int N_i N_j dOmega,
// integrated with the same 2-point Gauss rule and trilinear shapes as the
// elastic forces, so the discrete linear and angular momenta are the ones
// the stiffness sees. The 3N x 3N matrix has blocks m_ij I_3 in the node-major
// DOF order of the assembler (3 n + a).
#include <vector>

#include "fem/hex_mesh.hpp"

namespace msfab {

// Scalar (N x N) mass matrix m_ij. density[e] is element e's density
// (kg/m^3); InputError if the size is wrong or a density is not positive.
SpMat scalar_mass_matrix(const HexMesh& mesh, const std::vector<double>& density);
// The same integral with a non-negative weight per element (e.g. rho_e a_e
// for the Rayleigh mass-damping matrix); zero weights are allowed.
SpMat weighted_mass_matrix(const HexMesh& mesh, const std::vector<double>& weight);

// 3N x 3N matrix m_ij I_3, both triangles stored.
SpMat expand_to_dofs(const SpMat& scalar_mass);

// Mass, centre of mass and the second moment S = \int rho (x-c)(x-c)^T of the
// rest configuration, exact for the trilinear geometry because x is
// interpolated exactly: S = sum_ij m_ij (X_i - c)(X_j - c)^T.
struct MassProperties {
  double mass = 0;
  Vec3 center = Vec3::Zero();
  Mat3 second_moment = Mat3::Zero();
  // Inertia tensor about the centre: tr(S) I - S.
  Mat3 inertia() const { return second_moment.trace() * Mat3::Identity() - second_moment; }
};
MassProperties mass_properties(const SpMat& scalar_mass, const NodeArray& positions);

}  // namespace msfab
