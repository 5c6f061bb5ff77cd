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
#include <string>
#include <vector>

#include "fem/hex8.hpp"
#include "fem/voxel_grid.hpp"
#include "fem/voxel_stiffness_field.hpp"
#include "homog/elastic_tensor.hpp"
#include "solve/periodic_grid_multigrid.hpp"

namespace msfab {

struct HomogenizationOptions {
  // Void voxels get this fraction of the stiffest phase's element
  // stiffness ("ersatz material"), so a cell with void is never singular;
  // its bias on C^H is of this relative order.
  double void_stiffness = 1e-6;
  // Cell solver (the kinds of io/linear_solver_config.hpp): "cholmod"
  // (sparse Cholesky with one node pinned), "matrix-free" (multigrid-
  // preconditioned CG without an assembled matrix,
  // solve/periodic_grid_multigrid.hpp; every dimension even and at least 4),
  // or "auto": matrix-free for grids it supports from kAutoMultigridVoxels
  // voxels on, cholmod below.
  std::string solver = "auto";
  // Multigrid: relative residual at which CG stops. C^H is an energy, so its
  // error falls much faster than the residual: at 1e-6 it was below 1e-10
  // relative on random, inclusion and void-frame cells (docs/BENCHMARKS.md).
  double tolerance = 1e-6;
  // Matrix-free: CG iterations after which a solve fails, and the config key
  // that sets them (named in that message; empty: none).
  int max_iterations = 2000;
  std::string max_iterations_key;
  // Multigrid: Chebyshev smoother degree on the finest level (a tuning knob).
  int multigrid_smoother_degree = 2;
  // Multigrid: coarsening stops at this many lattice nodes (then a sparse
  // Cholesky); PeriodicMultigridOptions::coarsest_nodes.
  int multigrid_coarsest_nodes = PeriodicMultigridOptions{}.coarsest_nodes;
  // Multigrid: OpenMP threads (0: the OpenMP default).
  int threads = 0;
  // A 3D cell that maps onto itself under the cyclic axis permutation
  // x -> y -> z -> x (every cubic-symmetric cell does; see
  // cyclic_invariant) needs two cell problems, not six: the fluctuations of
  // yy and zz (xz and xy) are those of xx (yz) carried by the permutation.
  bool use_symmetry = true;
  // A 3D cell invariant under the three reflections i -> n - 1 - i (every
  // cubic and orthotropic gamut structure) is solved on one octant with
  // mirror conditions (homog/mirror_reduction.hpp): an eighth of the
  // unknowns, the same C^H. `solver` then picks the octant's solver.
  bool use_mirror_symmetry = true;
};

// True when the field is invariant under the cyclic permutation of the axes
// (voxel (i, j, k) -> (k, i, j)): a cube of voxels whose weights and
// element bases map onto themselves (to 1e-12 relative).
bool cyclic_invariant(const VoxelStiffnessField& field);

// "auto" switches to multigrid at this many voxels: from 12^3 on it is 2.4x
// faster than the direct solver or more, on one thread and on two; at 8^3
// the two are within 1.5x (docs/BENCHMARKS.md).
inline constexpr std::int64_t kAutoMultigridVoxels = 12 * 12 * 12;

struct HomogenizationResult {
  Mat6 C = Mat6::Zero();                // C^H, Voigt (elastic_tensor.hpp)
  Mat6 G = Mat6::Zero();                // harmonic displacements: strains under unit stresses, (C^H)^-1
  std::vector<double> volume_fraction;  // per palette id, [0] = void
  int pieces = 0;                       // connected solid pieces (voxels sharing a node, periodically)
  std::int64_t unknowns = 0;            // 3 per lattice node (direct: less the 3 pinned ones)
  std::string solver;                   // "cholmod" or "matrix-free"
  int iterations = 0;                   // multigrid: CG iterations over the strain cases solved
  bool symmetric_cases = false;         // two cases solved, four carried by the cyclic permutation
  bool octant = false;                  // solved on one octant (mirror symmetry); unknowns are the octant's
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

// The cell problem for any per-voxel element stiffness (element matrices of
// the 8-node hexahedron with corners voxel_corners(h)): the core of
// homogenize(), and of the continuous sampling step, whose voxels mix two
// materials. The stiffness must be positive definite up to rigid motions.
// volume_fraction and pieces are left empty. InputError for an invalid field
// or solver option (also "matrix-free" on a grid it cannot coarsen).
HomogenizationResult homogenize_elements(const VoxelStiffnessField& field, const HomogenizationOptions& options = {});

// The solver homogenize_elements() uses for this grid and option.
std::string homogenization_solver(int nx, int ny, int nz, const std::string& option);

// Peak memory of one cell's homogenization in bytes, for the stages'
// up-front memory checks (docs/cli.md, "Memory"); measured with
// /usr/bin/time on this code: a plane-strain cell (nz = 1) about 24 kB per
// voxel, the 3D multigrid about 1.3 kB per voxel, the 3D direct solver
// 3.3 kB x n^(4/3) for n voxels (its factor's fill). Whole-cell figures: an
// octant solve of a mirror-symmetric cell needs less.
double homogenization_peak_bytes(int nx, int ny, int nz, const std::string& option);

// Corner positions of one voxel of size h (corner a at (a>>2&1, a>>1&1, a&1) h).
hex8::NodeMatrix voxel_corners(double h);

// The element stiffness of a voxel of size h at rest (the material's
// Hessian at F = I, 2 x 2 x 2 Gauss points), corners as voxel_corners(h).
Mat24 voxel_stiffness(const MaterialPtr& material, double h);

// Columns m = 0..5: the total displacement (affine eps^m x plus the
// periodic fluctuation) at the 8 corners of `voxel`. Then
// C^H_mn = sum_v U_v^T K_v U_v / |Y|, and because the fluctuations are
// stationary, dC^H_mn / dK_v = U_v(:, m)^T dK_v U_v(:, n) / |Y| (no adjoint solve).
Eigen::Matrix<double, 24, 6> total_element_displacements(const HomogenizationResult& r, int nx, int ny, int nz,
                                                         double h, std::int64_t voxel);

// 2D, plane strain: the cell must have nz = 1. With one voxel across z and
// periodicity in z, every field is independent of z: the 3D cell problem
// is exactly the plane-strain problem of bilinear quadrilaterals (plus a
// decoupled anti-plane one). Voigt order xx, yy, xy (engineering shear).
struct PlaneStrainResult {
  Mat3 C = Mat3::Zero();  // in-plane block (xx, yy, xy) of the 3D C^H
  Mat3 G = Mat3::Zero();  // C^-1
  HomogenizationResult full;
};
PlaneStrainResult homogenize_plane_strain(const VoxelGrid& cell, const std::vector<MaterialPtr>& palette,
                                          const HomogenizationOptions& options = {});

// Engineering constants of a 2D tensor from its compliance S = C^-1:
// E_x = 1/S11, E_y = 1/S22, nu_xy = -S12/S11, G = 1/S33 (square symmetry:
// E_x = E_y).
struct PlaneModuli {
  double Ex = 0, Ey = 0, nu_xy = 0, G = 0;
};
PlaneModuli plane_moduli(const Mat3& C);

// Number of connected pieces of non-void voxels, two voxels being
// connected when they share a node across the periodic boundary too.
int count_periodic_pieces(const VoxelGrid& cell);

}  // namespace msfab
