#pragma once
// Hierarchical coarsening to level 2 (thesis §2.3.5, Fig. 2-8).
//
// A level-2 element replaces 2 x 2 x 2 level-1 elements, each carrying one of
// the k1 coarse materials of a (compressed) level-1 database: k1^8
// combinations, far too many to fit. Instead the level-1 elements are paired
// one axis at a time: 2 x 1 x 1 pairs (k1^2 candidates) are compressed to kx
// representatives, pairs of those along y (kx^2) to ky, pairs of those along
// z (ky^2) to kz. Each stage keeps only a lookup table (candidate ->
// representative); only the kz final arrangements are fitted (64-point
// elements, level2_block.hpp), and those parameters are what a level-2
// database stores.
//
// Features of a candidate (Eq. 2.10): log of its elastic energy under common
// smooth deformations of its bounding box's 8 corners, its other nodes
// relaxed (linear elasticity about the rest state: the candidate's stiffness
// condensed onto those corners). That is the energy a coarse element
// spanning the candidate would have to store, and what the thesis's
// intermediate fits approximate; we use it directly and save the
// k1^2 + kx^2 + ky^2 intermediate fits (docs/ddfem.md, "Level 2"). Imposing
// the deformation on every node instead made a soft half next to a stiff
// half invisible (the stiff half's energy dominates), and a soft/stiff cell
// was looked up to an almost all-stiff one.
#include <array>
#include <cstdint>
#include <vector>

#include "ddfem/coarse_fit.hpp"

namespace msfab {

// Level-1 entry of each child of a level-2 cell (child 4i + 2j + k, hex8
// order), -1 where a partial arrangement has no element.
using Arrangement = std::array<int, 8>;

// One pairing stage. Stage 0 pairs along x, 1 along y, 2 along z; its
// inputs are the previous stage's representatives (level-1 entries for
// stage 0).
struct PairStage {
  int inputs = 0;                              // size of the input alphabet
  std::vector<int> table;                      // a * inputs + b -> representative (b at the +axis side)
  std::vector<std::array<int, 2>> pairs;       // representative -> its (a, b)
  double mean_distance = 0, max_distance = 0;  // candidates to their representative (Eq. 2.10)
  int outputs() const { return static_cast<int>(pairs.size()); }
};

struct Level2Hierarchy {
  std::array<PairStage, 3> stages;
  // Over a level-1 database with void children: stage 0's alphabet has one
  // more letter, the all-void level-1 child (index void_entry()), so a
  // level-2 cell on an outline or in an odd grid's padding has a fit too.
  bool void_input = false;
  int level1_entries() const { return stages[0].inputs - (void_input ? 1 : 0); }
  int void_entry() const { return void_input ? stages[0].inputs - 1 : -1; }
  int num_final() const { return stages[2].outputs(); }
  // The final representative for the level-1 entries of a cell's 8 children
  // (all >= 0). Throws std::out_of_range on an entry outside the alphabet.
  int lookup(const Arrangement& level1_entries) const;
  // Level-1 entries of representative r of stage s (all 8 children for
  // s = 2; children 0 and 4 for s = 0; 0, 2, 4, 6 for s = 1).
  Arrangement arrangement(int stage, int r) const;
};

struct HierarchyOptions {
  std::array<int, 3> representatives{400, 400, 400};  // kx, ky, kz (the thesis: 400 each)
  int deformations = 32;                              // common deformations of the level-2 cell
  double strain = 0.05;                               // their strain magnitude
  std::uint64_t seed = 5;                             // draws the deformations and each stage's first representative
  // Add the 24 single-corner moves of the candidate's box to its features
  // (the diagonal of its condensed stiffness): where in the cell its
  // stiffness sits, as msfab-ddfem-compress's corner_moves.
  bool corner_moves = false;
  int features() const { return deformations + (corner_moves ? 24 : 0); }
};

// Common smooth deformations of the cube [0, L]^3: u(x) = L * strain *
// (A x/L + B q(x/L)), A a random 3 x 3 and B a random 3 x 6 matrix over the
// quadratic monomials q, each of unit Frobenius norm: stretch, shear,
// bending and twisting modes of the cell at once.
struct SmoothDeformation {
  Mat3 A;
  Eigen::Matrix<double, 3, 6> B;
  double length = 1, strain = 0;
  Vec3 at(const Vec3& x) const;
};
std::vector<SmoothDeformation> smooth_deformations(double length, int count, double strain, std::uint64_t seed);

// Rest stiffness (Hessian at rest) of each level-1 material as an element of
// edge `child_size`. InputError if one is not finite.
std::vector<Mat24> level1_rest_stiffness(const std::vector<CoarseMaterialFit>& level1, double child_size);

// Stiffness of a (partial) arrangement condensed onto the 8 corners of its
// bounding box (hex8 order), all other nodes relaxed; `extent` receives the
// box size in children per axis. Nodes are those of the 3 x 3 x 3 lattice of
// the cell; child c's element has the stiffness K1[arrangement[c]].
Mat24 condensed_stiffness(const Arrangement& arrangement, const std::vector<Mat24>& K1,
                          Eigen::Vector3i* extent = nullptr);

// Corner displacements (hex8 order) of a box of `extent` children of edge
// `child_size` at the cell's origin under a deformation.
Vec24 box_corner_displacements(const SmoothDeformation& d, const Eigen::Vector3i& extent, double child_size);

// Builds the three stages. A stage with at least as many representatives as
// candidates keeps every candidate (an exact lookup). With `void_input` the
// all-void level-1 child is one more input (no stiffness), seeded like a
// homogeneous material: all-void and solid/void layerings are kept exactly.
Level2Hierarchy build_level2_hierarchy(const std::vector<CoarseMaterialFit>& level1, double child_size,
                                       const HierarchyOptions& options, bool void_input = false);

}  // namespace msfab
