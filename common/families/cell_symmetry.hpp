#pragma once
// The 48 symmetries of a cubic unit cell about its centre, acting on
// unit-cell coordinates, and the voxels of the fundamental domain with the
// sizes of their orbits. Templates and their fits work on the fundamental
// domain only and mirror the result, which makes every cell they produce
// exactly cubic-symmetric whatever the floating-point rounding.
#include <array>
#include <vector>

#include "core/types.hpp"

namespace msfab {

// Signed permutation matrices, identity first, in a fixed order.
const std::array<Mat3, 48>& cell_symmetries();

// The image of p under S about the cell centre (1/2, 1/2, 1/2).
inline Vec3 apply_cell_symmetry(const Mat3& S, const Vec3& p) {
  const Vec3 c(0.5, 0.5, 0.5);
  return c + S * (p - c);
}

// The voxels (i, j, k) of an n^3 cell that gamut/structure_ops'
// fundamental_voxel maps onto themselves: i <= j <= k <= (n - 1) / 2,
// i.e. voxel centres in 0 <= x <= y <= z <= 1/2.
struct FundamentalVoxels {
  int n = 0;
  std::vector<std::array<int, 3>> voxel;  // in a fixed order
  std::vector<int> orbit_size;            // voxels of the cell the symmetries map it to
  std::vector<int> orbit_of;              // per voxel of the cell (x fastest): its entry in `voxel`
};
// InputError for n < 1.
FundamentalVoxels fundamental_voxels(int n);

}  // namespace msfab
