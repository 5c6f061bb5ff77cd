#pragma once
// Periodic linear-elastic homogenization of a voxel cell (thesis §3.2):
// for each of the six unit Voigt strains eps^m, the periodic fluctuation
// chi^m solves K chi^m = -K u^m (u^m = eps^m x, the affine field), and
//   C^H_mn = (1/|Y|) (u^m + chi^m)^T K (u^n + chi^n),
// the energy form, which is symmetric by construction. Trilinear 8-node
// hexahedra, one per voxel, 2 x 2 x 2 Gauss points; each phase's element
// stiffness is its material's Hessian at rest, so any Material works and
// is linearized at F = I. docs/homogenization.md.
#include <array>
#include <cstdint>
#include <vector>

#include "fem/voxel_grid.hpp"
#include "homog/elastic_tensor.hpp"

namespace msfab {

struct HomogenizationOptions {
  // Void voxels get this fraction of the stiffest phase's element
  // stiffness ("ersatz material"), so a cell with void is never singular;
  // its bias on C^H is of this relative order.
  double void_stiffness = 1e-6;
};

struct HomogenizationResult {
  Mat6 C = Mat6::Zero();          // C^H, Voigt (elastic_tensor.hpp)
  Mat6 G = Mat6::Zero();          // harmonic displacements: strains under unit stresses, (C^H)^-1
  std::vector<double> volume_fraction;  // per palette id, [0] = void
  int pieces = 0;                 // connected solid pieces (voxels sharing a node, periodically)
  std::int64_t unknowns = 0;      // 3 per lattice node, less the 3 pinned ones
  // Per Voigt strain: the periodic fluctuation at the nx*ny*nz lattice
  // nodes (3 per node, x fastest), zero at node 0.
  std::array<VecX, 6> fluctuation;
  double seconds = 0;
};

// palette[id] is the material of voxel id (palette[0], void, is ignored).
// InputError for an empty or all-void cell, a voxel id without a material,
// or a non-positive void_stiffness; NumericalError if the system is not
// positive definite.
HomogenizationResult homogenize(const VoxelGrid& cell, const std::vector<MaterialPtr>& palette,
                                const HomogenizationOptions& options = {});

// Number of connected pieces of non-void voxels, two voxels being
// connected when they share a node across the periodic boundary too.
int count_periodic_pieces(const VoxelGrid& cell);

}  // namespace msfab
