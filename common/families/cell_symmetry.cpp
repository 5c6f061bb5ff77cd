#include "families/cell_symmetry.hpp"

#include <algorithm>
#include <string>

#include "core/errors.hpp"
#include "gamut/structure_ops.hpp"

namespace msfab {

const std::array<Mat3, 48>& cell_symmetries() {
  static const std::array<Mat3, 48> all = [] {
    std::array<Mat3, 48> out;
    std::array<int, 3> perm{0, 1, 2};
    int s = 0;
    do {
      for (int signs = 0; signs < 8; ++signs) {
        Mat3 m = Mat3::Zero();
        for (int r = 0; r < 3; ++r) m(r, perm[r]) = (signs >> r & 1) ? -1.0 : 1.0;
        out[s++] = m;
      }
    } while (std::next_permutation(perm.begin(), perm.end()));
    return out;
  }();
  return all;
}

FundamentalVoxels fundamental_voxels(int n) {
  if (n < 1) throw InputError("fundamental_voxels: cell resolution must be at least 1, got " + std::to_string(n));
  FundamentalVoxels f;
  f.n = n;
  // Only the shape of the grid matters to fundamental_voxel; sharing it
  // keeps one convention for "the fundamental domain" across the code.
  const VoxelGrid shape(n, n, n, 1.0 / n);
  std::vector<int> entry(shape.size(), -1);
  f.orbit_of.assign(shape.size(), -1);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const auto r = fundamental_voxel(shape, i, j, k);
        const std::size_t rep = shape.index(r[0], r[1], r[2]);
        if (entry[rep] < 0) {
          entry[rep] = static_cast<int>(f.voxel.size());
          f.voxel.push_back(r);
          f.orbit_size.push_back(0);
        }
        f.orbit_of[shape.index(i, j, k)] = entry[rep];
        ++f.orbit_size[entry[rep]];
      }
  return f;
}

}  // namespace msfab
