#pragma once
// Force-space sampling of a fine block's deformation space (thesis §2.3.2):
// self-equilibrated nodal force sets (stretching, shearing, bending,
// twisting along several directions, pinching along the twelve cube edges)
// at several magnitudes and both signs, each solved as a nonlinear static
// problem. A sample is the displacement of the eight block corners (the
// coarse element's u^1 = r(u^0) of Eq. 2.8) and the fine elastic energy V^0.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "ddfem/fine_block.hpp"
#include "fem/elastic_assembler.hpp"

namespace msfab {

enum class ForceKind { stretch, shear, bend, twist, pinch };
std::string force_kind_name(ForceKind kind);

struct ForceSamplingOptions {
  // Directions for stretch / shear / bend / twist: the three axes (if
  // include_axes) plus `sphere_directions` points of a Fibonacci hemisphere
  // turned by a rotation drawn from `seed`.
  bool include_axes = true;
  int sphere_directions = 3;
  int magnitudes = 5;        // per sign; magnitude m of n is m/n of the largest
  double max_strain = 0.15;  // small-strain estimate of the largest local strain at the largest magnitude
  std::uint64_t seed = 1;
  double newton_tolerance = 1e-9;
  // Where the block is while it is sampled (docs/ddfem.md, "In-situ
  // sampling"):
  //  isolated: alone, loaded by the force patterns (thesis §2.3.2);
  //  patch:    surrounded by `context` layers of its own periodic copies,
  //            loaded by stress fields on the patch's outer faces (the
  //            builder makes such blocks with make_fine_block(..., context));
  //  periodic: among infinitely many periodic copies, corner displacements
  //            prescribed and the periodic fluctuation relaxed
  //            (periodic_samples.hpp).
  // The kinds sampled, by ForceKind (periodic sampling; all by default).
  std::array<bool, 5> kinds{true, true, true, true, true};
  enum class Mode { isolated, patch, periodic };
  Mode mode = Mode::isolated;
  int context = 1;  // patch mode: voxels of periodic copies on each side
};
// "isolated", "patch", "periodic"; parse_sampling_mode throws InputError on
// anything else.
std::string sampling_mode_name(ForceSamplingOptions::Mode mode);
ForceSamplingOptions::Mode parse_sampling_mode(const std::string& name);

// A unit-norm, self-equilibrated nodal force set on the block's mesh.
struct ForcePattern {
  ForceKind kind = ForceKind::stretch;
  Vec3 direction = Vec3::UnitX();  // stretch / shear / bend / twist axis; pinch: edge direction
  Vec3 second = Vec3::Zero();      // shear / bend: the transverse direction; pinch: first corner's position
  VecX force;                      // per DOF
};

struct ForceSample {
  int pattern = 0;                            // index into ForceSampleSet::patterns
  double load = 0;                            // signed multiple of the unit pattern applied
  Vec24 corner_displacement = Vec24::Zero();  // coarse u^1, node-major (3*corner + axis)
  double energy = 0;                          // fine elastic energy V^0 at equilibrium
  int newton_iterations = 0;
};

struct ForceSampleSet {
  std::vector<ForcePattern> patterns;
  std::vector<ForceSample> samples;  // converged samples, in pattern, sign, magnitude order
  int attempted = 0;
  int dropped = 0;     // solves that did not converge
  double seconds = 0;  // wall time of the solves
};

// The fine block's static problem with rigid motion removed by six linear
// constraints on the displacement u: zero mean translation, sum_i u_i = 0,
// and zero mean infinitesimal rotation, sum_i (X_i - c) x u_i = 0 (c the
// node centroid), over every node of the mesh (the block and its context).
//
// Why not three pinned corners (a 3-2-1 support): with dead loads a
// compressive or shearing pattern makes the block rotate about the pinned
// corner once the strain reaches a few percent, since single nodes resist
// moments only through local deformation, and Newton then lands on rotated
// or flipped states whose corner displacements are not deformations. The
// averaged rotation constraint acts on all nodes, like the rest of the body
// around a coarse element would. Requires all eight corners
// (std::invalid_argument otherwise). The block must outlive the solver.
//
// Two linear algebra paths, chosen by size. The isolated block (75
// unknowns) runs a dense Newton in an orthonormal basis Z of the
// constraints' null space, x = X + Z y. A block in context (hundreds to
// thousands of unknowns) solves each Newton step's KKT system with a sparse
// LDL^T of K + sigma I (sigma tiny, only to make K's rigid modes
// invertible) and a 6 x 6 Schur complement on the constraints; the inertia
// of the two factors tells whether K is positive definite on the
// constraints' null space, as the dense path's LDL^T of Z^T K Z does.
class BlockSolver {
 public:
  explicit BlockSolver(const FineBlock& block, double newton_tolerance = 1e-9);
  ~BlockSolver();

  const FineBlock& block() const { return block_; }
  const ElasticAssembler& assembler() const { return assembler_; }
  // The constraint matrix G (6 x DOFs): G u = 0. Its rows are the
  // translation and rotation modes, so G f is the net force and moment of
  // a nodal force set f.
  const MatX& constraint_matrix() const { return G_; }
  // Orthonormal null-space basis Z (DOFs x (DOFs - 6)); empty on the
  // sparse path.
  const MatX& null_space() const { return Z_; }
  bool sparse() const { return sparse_ != nullptr; }

  // Largest local small strain (largest |eigenvalue| of sym grad u over the
  // block's own fine quadrature points) of the linearized response to `force`.
  double linear_peak_strain(const VecX& force) const;

  struct Solution {
    bool converged = false;
    VecX x;             // deformed positions
    double energy = 0;  // fine elastic energy of the block's own elements
    int iterations = 0;
  };
  // Nonlinear solve under `force` by Newton with backtracking line search,
  // starting from x0 (rest if empty; x0 must satisfy the constraints, as
  // every returned x does).
  Solution solve(const VecX& force, const VecX& x0 = VecX()) const;

  // Corner displacements (24) of a deformed configuration.
  Vec24 corner_displacements(const VecX& x) const;

 private:
  struct SparseKkt;
  // The constrained Newton step for Hessian K and residual r (= g - f):
  // minimizes 1/2 d^T K d + r^T d over G d = 0, shifting K by multiples of
  // the identity until it is positive definite on the null space. Returns
  // false if no shift gave a descent direction.
  bool newton_step(const SpMat& K, const VecX& r, VecX& step) const;
  double block_energy(const VecX& x) const;

  const FineBlock& block_;
  ElasticAssembler assembler_;
  HexMesh core_mesh_;  // the block's own elements (all nodes); empty when isolated
  std::unique_ptr<ElasticAssembler> core_assembler_;
  double tolerance_;
  int max_iterations_ = 200;  // slow cases: a soft corner next to stiff children
  MatX G_, Z_;
  VecX rest_;
  double stiffness_scale_ = 0;              // largest diagonal entry of the rest stiffness (projected when dense)
  Eigen::LDLT<MatX> rest_stiffness_;        // dense path: Z^T K(X) Z
  std::unique_ptr<SparseKkt> sparse_;       // Newton iterations (refactored each step)
  std::unique_ptr<SparseKkt> sparse_rest_;  // the rest state, for linear_peak_strain
};

// Removes the net force and net moment (about the node centroid) of a nodal
// force set with the least change, leaving it self-equilibrated.
VecX self_equilibrate(const HexMesh& mesh, const VecX& force);

// The unit force patterns for a block (deterministic for given options).
std::vector<ForcePattern> make_force_patterns(const FineBlock& block, const ForceSamplingOptions& options);
// The transverse direction t of the shear and bend patterns along d: a unit
// vector orthogonal to d, the next axis for an axis (x -> y -> z -> x).
Vec3 sampling_transverse(const Vec3& d);
// The smooth families as vector fields of r, the position from the block
// centre in voxel units: nodal forces of isolated sampling, corner
// displacements of periodic sampling. stretch d (d.r); shear
// d (t.r) + t (d.r); bend d (d.r)(t.r) (axial, linear across the neutral
// plane, opposite at the ends); twist (d x r)(d.r). Not for pinch.
Vec3 family_field(ForceKind kind, const Vec3& d, const Vec3& t, const Vec3& r);
// The smooth families in pattern order (per direction).
inline constexpr std::array<ForceKind, 4> kSmoothFamilies{ForceKind::stretch, ForceKind::shear, ForceKind::bend,
                                                          ForceKind::twist};
// The family's second pattern vector: t for shear and bend, else zero.
inline Vec3 family_second(ForceKind kind, const Vec3& t) {
  return kind == ForceKind::shear || kind == ForceKind::bend ? t : Vec3::Zero();
}
// The pinching pairs in pattern order: every edge of the cube as corners
// a < b that differ in one bit, with the edge's axis (bit 2 is x, bit 0 is z).
template <class Visit>
void for_each_cube_edge(Visit&& visit) {
  for (int a = 0; a < 8; ++a)
    for (int bit = 0; bit < 3; ++bit) {
      const int b = a | (1 << bit);
      if (b != a) visit(a, b, Vec3(Vec3::Unit(2 - bit)));
    }
}
// Sampling directions: axes then the seeded Fibonacci hemisphere.
std::vector<Vec3> sampling_directions(bool include_axes, int sphere_directions, std::uint64_t seed);

// InputError unless magnitudes >= 1 and max_strain > 0.
void check_sampling_options(const ForceSamplingOptions& options);

// The continuation every sampler runs: for each pattern p whose scale(p) is
// > 0, in both signs, magnitudes m = 1..options.magnitudes at the load
// sign scale(p) m / magnitudes in increasing order, each started from the
// state the last kept sample left (`state`, empty at first: a continuation
// that keeps Newton short). solve() fills the sample and returns false to
// drop it (a solve that did not converge), leaving `state` as it was.
using PatternSolve = std::function<bool(int pattern, double load, VecX& state, ForceSample& sample)>;
ForceSampleSet sample_patterns(std::vector<ForcePattern> patterns, const ForceSamplingOptions& options,
                               const std::function<double(int pattern)>& scale, const PatternSolve& solve);

// Runs every pattern at options.magnitudes magnitudes in both signs. Each
// pattern's largest load is scaled so its linear response peaks at
// options.max_strain, so soft and stiff blocks deform comparably.
ForceSampleSet sample_force_space(const FineBlock& block, const ForceSamplingOptions& options);

}  // namespace msfab
