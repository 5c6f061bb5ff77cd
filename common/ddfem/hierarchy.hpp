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
// smooth deformations of the level-2 cell, summed over the level-1 elements
// it is made of. The thesis fits a coarse material to each intermediate
// candidate and compares those; we compare the arrangements' own energies,
// which the intermediate fit would only approximate, and save the
// k1^2 + kx^2 + ky^2 intermediate fits (docs/ddfem.md, "Level 2").
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
  int inputs = 0;                          // size of the input alphabet
  std::vector<int> table;                  // a * inputs + b -> representative (b at the +axis side)
  std::vector<std::array<int, 2>> pairs;   // representative -> its (a, b)
  double mean_distance = 0, max_distance = 0;  // candidates to their representative (Eq. 2.10)
  int outputs() const { return static_cast<int>(pairs.size()); }
};

struct Level2Hierarchy {
  std::array<PairStage, 3> stages;
  int level1_entries() const { return stages[0].inputs; }
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
  int deformations = 32;    // common deformations of the level-2 cell
  double strain = 0.05;     // their strain magnitude
  std::uint64_t seed = 5;   // draws the deformations and each stage's first representative
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

// Energy of each level-1 entry placed at each child position of the cell
// (child edge `child_size`) under each deformation: [entry][child][def].
// InputError if an energy is not positive and finite.
std::vector<std::array<std::vector<double>, 8>> child_energies(const std::vector<CoarseMaterialFit>& level1,
                                                               double child_size,
                                                               const std::vector<SmoothDeformation>& defs);

// Builds the three stages. A stage with at least as many representatives as
// candidates keeps every candidate (an exact lookup).
Level2Hierarchy build_level2_hierarchy(const std::vector<CoarseMaterialFit>& level1, double child_size,
                                       const HierarchyOptions& options);

}  // namespace msfab
