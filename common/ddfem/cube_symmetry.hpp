#pragma once
// The 48 symmetries of the cube (rotations and reflections), acting on the
// eight children of a fine block and on a coarse material fit. The database
// builder fits one block per orbit of material combinations and maps the
// result to the other members, which is exact: the coarse element, its
// Gauss points and the Eq. 2.7 energy are all carried onto themselves.
#include <array>
#include <vector>

#include "ddfem/coarse_fit.hpp"

namespace msfab {

struct CubeSymmetry {
  Mat3 matrix = Mat3::Identity();  // signed permutation acting on centred coordinates
  std::array<int, 8> child{};      // child c (hex8 order) goes to child[c]
};

// All 48, identity first, in a fixed order.
const std::vector<CubeSymmetry>& cube_symmetries();

// ids'[S.child[c]] = ids[c].
BlockMaterials apply_symmetry(const CubeSymmetry& S, const BlockMaterials& ids);

// The orbit's representative: the lexicographically smallest image of ids
// over the 48 symmetries, and one symmetry that maps ids onto it.
struct CanonicalBlock {
  BlockMaterials ids{};
  int symmetry = 0;  // index into cube_symmetries(): apply_symmetry(S, input) == ids
};
CanonicalBlock canonical_block(const BlockMaterials& ids);

// The fit of block B from the fit of its image B' = S(B): quadrature point
// k of B takes the parameters of point S.child[k] of B' and the spring
// direction S^T v'. Errors and sample counts are the representative's.
CoarseMaterialFit map_fit_back(const CubeSymmetry& S, const CoarseMaterialFit& image, const BlockMaterials& ids);

}  // namespace msfab
