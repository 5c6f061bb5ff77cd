#pragma once
// A periodic voxel cell under finite uniaxial stress (thesis §3.3: the
// auxetic families were designed with linear elasticity and checked with
// a Neo-Hookean material up to 7% strain).
//
// The cell's deformation is x = S X + w(X): S = diag of the stretches,
// the one along `axis` prescribed and the two lateral ones free, and w a
// fluctuation periodic on the cell. The total energy is minimized over w
// and the lateral stretches together: the macroscopic lateral stress is
// zero where the energy is stationary in them, so this is uniaxial stress
// along `axis`. The macroscopic shears are held at zero, which is exact for
// a cell with the three mirror symmetries (every gamut structure): its
// normal strains do not couple to shear.
//
// Void carries no unknowns (no ersatz material: at finite strain an
// ersatz void element can invert and stop the Newton iteration); the solid
// must be one piece that spans the cell periodically. Materials are used
// as given: Neo-Hookean for the finite-strain check; a linear material
// reproduces the linear C^H's Poisson ratio at any strain.
#include <array>
#include <vector>

#include "core/types.hpp"
#include "fem/hex8.hpp"
#include "fem/voxel_grid.hpp"
#include "material/material.hpp"

namespace msfab {

class PeriodicFiniteStrainCell {
 public:
  // palette[id] is the material of voxel id (palette[0], void, ignored).
  // InputError for an all-void cell, an id without a material, or a solid
  // of more than one piece; axis in 0..2. Keeps references to `cell` and
  // `palette`, which must outlive it.
  PeriodicFiniteStrainCell(const VoxelGrid& cell, const std::vector<MaterialPtr>& palette, int axis);

  // Unknowns z: the fluctuation at every node touched by the solid but the
  // first (held at zero: the translation), 3 per node, then the two lateral
  // stretches (the axes after `axis`, cyclically).
  int unknowns() const { return 3 * free_nodes_ + 2; }
  int axis() const { return axis_; }
  // z at rest: zero fluctuation, unit lateral stretches.
  VecX rest() const;
  // The stretches (x, y, z) at axial stretch s and unknowns z.
  Vec3 stretches(double s, const VecX& z) const;

  // Total energy at axial stretch s (+inf if an element is inverted);
  // optionally its gradient and Hessian in z (the Hessian's upper and
  // lower triangles) and dE/ds, the axial force times the cell length.
  double energy(double s, const VecX& z, VecX* gradient, SpMat* hessian, double* dE_ds = nullptr) const;
  double volume() const { return volume_; }  // the cell's reference volume |Y|
  // mu h^3 of the stiffest material: the scale of an element's energy at unit strain.
  double energy_scale() const { return energy_scale_; }

 private:
  const VoxelGrid& cell_;
  const std::vector<MaterialPtr>& palette_;
  int axis_;
  int lateral_[2];
  int free_nodes_ = 0;
  std::vector<std::size_t> solid_;  // voxel indices with material
  // Per solid voxel, its corners' first unknowns (-1: the held node).
  std::vector<std::array<int, 8>> element_unknowns_;
  hex8::NodeMatrix corners_;  // one voxel's corners at the origin
  hex8::ElementGeometry geometry_;
  double volume_ = 0, energy_scale_ = 0;
};

struct FiniteStrainOptions {
  double max_step = 0.01;          // largest strain increment of the continuation
  int max_newton_iterations = 50;  // per increment
  // Newton stops when its decrement -g.dz falls below this times the
  // energy scale (mu h^3 of the stiffest material times the solid voxels).
  double newton_tolerance = 1e-14;
};

struct UniaxialStrainPoint {
  double strain = 0;  // engineering strain along the axis, s - 1
  Vec3 stretch = Vec3::Ones();
  double nu[2] = {0, 0};      // secant Poisson ratios -(lateral stretch - 1) / strain, lateral axes in order
  double nominal_stress = 0;  // axial force per reference cross-section (first Piola-Kirchhoff)
  int newton_iterations = 0;  // over the increments that reached this strain
  // Of those iterations, how many needed a shifted Hessian: the solid has
  // a zero-energy mechanism (voxels hinged at a shared node or edge), or
  // it buckled on the way to this strain.
  int shifted_factorizations = 0;
};

// Uniaxial stress at the engineering strains `strains` (nonzero, > -1),
// each reached by continuation from rest in steps of at most max_step;
// results in the order given. NumericalError when Newton does not converge
// or the stiffness is not positive definite even with a shift of 100 times
// its diagonal. A singular or indefinite stiffness (a hinge, a buckling
// beam) is shifted until it is positive definite.
std::vector<UniaxialStrainPoint> uniaxial_finite_strain(const VoxelGrid& cell, const std::vector<MaterialPtr>& palette,
                                                        int axis, const std::vector<double>& strains,
                                                        const FiniteStrainOptions& options = {});

}  // namespace msfab
