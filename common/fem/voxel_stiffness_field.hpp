#pragma once
// Element stiffness matrices of a periodic voxel grid, one 8-node hexahedron
// per voxel, each a weighted sum of a few base matrices:
//   K_v = sum_b weight(v, b) basis[b].
// A palette of materials is the one-hot case; a SIMP mix of two materials
// (the continuous gamut step) has weights (1, rho_v^p) on (K_soft, K_stiff -
// K_soft). The form keeps a 64^3 cell at a few numbers per voxel, lets the
// multigrid solver apply K without storing it, and makes its Galerkin
// coarse operators linear in the weights.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace msfab {

struct VoxelStiffnessField {
  int nx = 0, ny = 0, nz = 0;
  double h = 1.0;               // voxel edge length
  std::vector<Mat24> basis;     // corner a at (a>>2&1, a>>1&1, a&1) h; 3 unknowns per corner
  std::vector<double> weights;  // basis.size() per voxel, voxel v = i + nx (j + ny k)

  std::int64_t voxels() const { return std::int64_t(nx) * ny * nz; }
  int basis_size() const { return static_cast<int>(basis.size()); }
  double weight(std::int64_t v, int b) const { return weights[std::size_t(v) * basis.size() + b]; }
  Mat24 element(std::int64_t v) const;
};

// A point symmetry of the voxel that sends corner a to corner[a] and
// displacement component r to sign[r] times component[r]: true when every
// basis matrix maps onto itself under it (to 1e-12 of its largest entry).
struct VoxelSymmetry {
  std::array<int, 8> corner;
  std::array<int, 3> component;
  std::array<double, 3> sign;
};
bool basis_invariant(const VoxelStiffnessField& field, const VoxelSymmetry& symmetry);

// True when voxels v and w carry the same weights (to 1e-12 relative).
bool same_weights(const VoxelStiffnessField& field, std::int64_t v, std::int64_t w);

// Throws InputError ("<what>: ...") for empty dimensions, a non-positive
// voxel size, no basis, or a weight table of the wrong size or with a
// non-finite entry.
void validate_field(const VoxelStiffnessField& field, const std::string& what);

}  // namespace msfab
