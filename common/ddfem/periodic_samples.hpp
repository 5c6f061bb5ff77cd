#pragma once
// Kinematic in-situ sampling of a block (docs/ddfem.md, "In-situ
// sampling"): the block among infinitely many periodic copies of itself.
//
// A sample prescribes the coarse element's corner displacements u1 (the
// same stretch, shear, bend, twist and pinch families as the force-space
// sampling, as displacement fields evaluated at the corners) and relaxes
// the block: x = X + U(X) + w(X), U the trilinear interpolation of u1 and w
// a fluctuation periodic on the block, zero at the corners. The sample's
// energy is min_w of the fine energy. For an affine u1 this is periodic
// homogenization of the block (a fibre or a layer continues through the
// block's faces, as in a body); for a homogeneous block it is then exactly
// the coarse element's energy. Isolated, force-loaded sampling instead lets
// a stiff fibre segment carry load only through the soft matrix around it.
#include "ddfem/anisotropy.hpp"
#include "ddfem/force_samples.hpp"

namespace msfab {

// The unit corner-displacement patterns (24 values in ForcePattern::force,
// node-major) of the families: stretch d (d.r), shear d (t.r) + t (d.r),
// bend d (d.r)(t.r), twist (d x r)(d.r) with r the corner's position from
// the block centre in voxels, plus the two corners of each cube edge moved
// towards each other. Each is scaled so the coarse element's largest
// small-strain eigenvalue over its Gauss points is 1.
std::vector<ForcePattern> make_corner_displacement_patterns(const FineBlock& block,
                                                            const ForceSamplingOptions& options);

// The relaxed fine energy min_w E(X + U + w) for corner displacements u1.
// `w` carries the periodic fluctuation in (a warm start) and out, one Vec3
// per periodic node class of the (n + 1)^3 lattice (n^3 classes, the
// corners' class held at zero). Returns +inf if Newton does not converge.
class PeriodicBlockSolver {
 public:
  explicit PeriodicBlockSolver(const FineBlock& block, double newton_tolerance = 1e-9);
  double relax(const Vec24& u1, VecX& w, int* iterations = nullptr) const;
  // Deformed positions for corner displacements u1 and fluctuation w.
  VecX positions(const Vec24& u1, const VecX& w) const;
  // The coarse element's corner displacements of the relaxed block: u1 at
  // corners with a fine node; at a corner whose child is void (no fine
  // node), the value for which the trilinear field of the corners best
  // matches the fine displacements at the block's nodes (least squares).
  // There the corner is not held by the block, and the fine block relaxes
  // through it (a slab with void above contracts freely across its
  // thickness): the sample records that relaxed corner, as a coarse element
  // in a body finds it, instead of the prescribed one, which the fine energy
  // does not depend on.
  Vec24 corner_displacements(const Vec24& u1, const VecX& w) const;

 private:
  const FineBlock& block_;
  ElasticAssembler assembler_;
  double tolerance_;
  int free_ = 0;            // 3 per periodic class with nodes, corners' class excepted
  double force_round_off_;  // mu h^2 of the stiffest fine material: nodal forces' scale at round-off
  VecX rest_;
  std::vector<int> node_class_;  // mesh node -> its periodic class's unknown, -1 at the corners
  std::vector<Eigen::Matrix<double, 8, 1>> node_weights_;  // trilinear weights of the corners at each node
  MatX reduce_;                    // DOFs x free_: sums nodal forces over each free periodic class
  std::vector<int> void_corners_;  // corners without a fine node
  MatX extrapolate_;               // (3 void corners) x 21: their least-squares correction from w
};

// Every pattern at options.magnitudes magnitudes in both signs, peak coarse
// strain options.max_strain at the largest, each magnitude started from the
// previous one's fluctuation. Blocks with void children are sampled the
// same way (docs/ddfem.md, "Blocks with void").
ForceSampleSet sample_periodic(const FineBlock& block, const ForceSamplingOptions& options);

// The spring direction of a block sampled among periodic copies, for blocks
// whose isolated stretching (estimate_anisotropy) is not defined (a void
// child leaves a corner without a fine node): of `directions` seeded
// hemisphere directions d, the one whose relaxed uniaxial strain
// strain * d (d . X) stores the most energy, i.e. the stiffest. One
// direction for all points of the block.
Vec3 stiffest_periodic_direction(const FineBlock& block, int directions, double strain, std::uint64_t seed,
                                 double newton_tolerance = 1e-9);

// Per-point spring directions of a block of 4 x 4 x 4 voxels among its
// periodic copies. Its coarse points lie one in each voxel, and an affine
// coarse field tells them apart only through the fine field: for each of
// `directions` seeded directions d the block is relaxed under the uniaxial
// strain `strain` d (d . X), and the voxel under point q stores the energy
// W_q(d). Displacement-controlled, a voxel is stiffest where it stores the
// most, so the point's direction is the one where its compliance
// 1 / sqrt(W_q(d)) is least: the smallest singular vector of the points
// +-d / sqrt(W_q(d)), as estimate_anisotropy does with the stretches of
// force-controlled samples. Points in void voxels take x. Throws
// NumericalError if fewer than 3 directions relax.
std::vector<Vec3> periodic_point_directions(const FineBlock& block, const AnisotropyOptions& options);

}  // namespace msfab
