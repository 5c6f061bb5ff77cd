#include "ddfem/cube_symmetry.hpp"

#include <algorithm>
#include <stdexcept>

namespace msfab {

const std::vector<CubeSymmetry>& cube_symmetries() {
  static const std::vector<CubeSymmetry> all = [] {
    std::vector<CubeSymmetry> out;
    std::array<int, 3> perm{0, 1, 2};
    do {
      for (int signs = 0; signs < 8; ++signs) {
        CubeSymmetry S;
        S.matrix.setZero();
        for (int r = 0; r < 3; ++r) S.matrix(r, perm[r]) = (signs >> r & 1) ? -1.0 : 1.0;
        for (int c = 0; c < 8; ++c) {
          // Child c sits at centred position s = 2 (i, j, k) - 1.
          const Vec3 s(2.0 * (c >> 2 & 1) - 1, 2.0 * (c >> 1 & 1) - 1, 2.0 * (c & 1) - 1);
          const Vec3 t = S.matrix * s;
          S.child[c] = 4 * (t.x() > 0) + 2 * (t.y() > 0) + (t.z() > 0);
        }
        out.push_back(S);
      }
    } while (std::next_permutation(perm.begin(), perm.end()));
    return out;
  }();
  return all;
}

BlockMaterials apply_symmetry(const CubeSymmetry& S, const BlockMaterials& ids) {
  BlockMaterials out{};
  for (int c = 0; c < 8; ++c) out[S.child[c]] = ids[c];
  return out;
}

CanonicalBlock canonical_block(const BlockMaterials& ids) {
  CanonicalBlock best{ids, 0};
  const auto& all = cube_symmetries();
  for (int s = 1; s < static_cast<int>(all.size()); ++s) {
    const BlockMaterials image = apply_symmetry(all[s], ids);
    if (image < best.ids) best = {image, s};
  }
  return best;
}

CoarseMaterialFit map_fit_back(const CubeSymmetry& S, const CoarseMaterialFit& image, const BlockMaterials& ids) {
  if (image.points() != 8) throw std::invalid_argument("map_fit_back: level-1 fits (8 points) only");
  CoarseMaterialFit fit = image;
  fit.material_ids = ids;
  for (int k = 0; k < 8; ++k) {
    // Point k of the 2-point rule lies in child k (hex8 bit order).
    const int j = S.child[k];
    fit.mu[k] = image.mu[j];
    fit.lambda[k] = image.lambda[j];
    fit.C[k] = image.C[j];
    fit.mu0[k] = image.mu0[j];
    fit.lambda0[k] = image.lambda0[j];
    fit.v[k] = S.matrix.transpose() * image.v[j];
  }
  return fit;
}

}  // namespace msfab
