#pragma once
// The cell problem of a mirror-symmetric cell solved on one octant.
//
// Every structure of a cubic or orthotropic gamut is invariant under the
// three reflections voxel i -> n - 1 - i (structure_ops.hpp). On a periodic
// cell a reflection about the plane x = 0 is also one about x = L/2, so the
// octant [0, L/2]^3 is a fundamental domain, bounded by mirror planes on
// all six sides. The fluctuation of strain case m inherits a parity under
// each reflection R_d: chi(R_d x) = s_md R_d chi(x), with s_md = -1 when
// R_d flips the sign of the unit strain (shear cases whose axes contain d)
// and +1 otherwise. On a mirror plane of axis d that parity pins
//   s_md = +1: the normal component chi_d = 0 (a roller),
//   s_md = -1: the two tangential components (the normal one is free),
// and the full-cell energy of such a field is 8 times the octant's. So the
// octant problem with those zero conditions has the full cell's
// fluctuation as its unique solution (the pins also remove the periodic
// translations; the solution is zero at node 0, the gauge of the full
// solvers). The three normal cases share one set of conditions, each shear
// case has its own. The octant has 1/8 of the voxels and no periodic
// wrap, so it is solved by the Dirichlet grid multigrid or a sparse
// Cholesky factorization of an eighth of the size (docs/homogenization.md).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "fem/voxel_stiffness_field.hpp"

namespace msfab {

// True for a 3D field (every dimension even, nz > 1) whose element bases
// and weights map onto themselves under the three reflections
// (to 1e-12 relative).
bool mirror_invariant(const VoxelStiffnessField& field);

struct OctantSolverOptions {
  std::string solver = "auto";     // auto | cholmod | matrix-free (Dirichlet grid multigrid on the octant)
  double tolerance = 1e-6;         // matrix-free: relative residual
  int max_iterations = 2000;       // matrix-free: CG iterations before it fails
  std::string max_iterations_key;  // the config key of max_iterations, for messages
  int smoother_degree = 2;
  int threads = 0;
};

struct OctantSolveReport {
  std::string solver;         // "cholmod" or "matrix-free"
  std::int64_t unknowns = 0;  // free octant unknowns, largest over the case groups
  int iterations = 0;         // multigrid: CG iterations over the cases solved
};

// "auto" solves octants of up to this many voxels directly (a 16^3 cell),
// by the grid multigrid above, where it was faster on one thread and two
// (docs/BENCHMARKS.md, "Mirror symmetry").
inline constexpr std::int64_t kAutoOctantMultigridVoxels = 8 * 8 * 8;

// The solver solve_on_octant() uses for a field of this size and option.
// InputError for an unknown option.
std::string octant_solver(const VoxelStiffnessField& field, const std::string& option);

// Solves the strain cases `cases` (Voigt 0..5) of a mirror_invariant()
// field on its octant and writes their fluctuations on the full periodic
// lattice (3 per node, node i + nx (j + ny k)) into fluctuation[m].
// NumericalError if the octant's stiffness is not positive definite.
OctantSolveReport solve_on_octant(const VoxelStiffnessField& field, const std::vector<int>& cases,
                                  const OctantSolverOptions& options, std::array<VecX, 6>& fluctuation);

}  // namespace msfab
