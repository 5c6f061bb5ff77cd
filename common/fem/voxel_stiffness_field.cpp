#include "fem/voxel_stiffness_field.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/errors.hpp"

namespace msfab {

Mat24 VoxelStiffnessField::element(std::int64_t v) const {
  Mat24 K = Mat24::Zero();
  for (int b = 0; b < basis_size(); ++b)
    if (const double w = weight(v, b); w != 0.0) K += w * basis[b];
  return K;
}

bool basis_invariant(const VoxelStiffnessField& field, const VoxelSymmetry& g) {
  for (const Mat24& K : field.basis) {
    const double tol = 1e-12 * K.cwiseAbs().maxCoeff();
    for (int a = 0; a < 8; ++a)
      for (int b = 0; b < 8; ++b)
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c)
            if (std::abs(g.sign[r] * g.sign[c] * K(3 * g.corner[a] + g.component[r], 3 * g.corner[b] + g.component[c]) -
                         K(3 * a + r, 3 * b + c)) > tol)
              return false;
  }
  return true;
}

bool same_weights(const VoxelStiffnessField& field, std::int64_t v, std::int64_t w) {
  for (int b = 0; b < field.basis_size(); ++b)
    if (std::abs(field.weight(v, b) - field.weight(w, b)) > 1e-12 * std::max(std::abs(field.weight(v, b)), 1e-300))
      return false;
  return true;
}

void validate_field(const VoxelStiffnessField& field, const std::string& what) {
  if (field.nx < 1 || field.ny < 1 || field.nz < 1) throw InputError(what + ": the cell has no voxels");
  if (!(field.h > 0) || !std::isfinite(field.h)) throw InputError(what + ": the voxel size must be > 0");
  if (field.basis.empty()) throw InputError(what + ": no element stiffness matrices");
  if (field.weights.size() != std::size_t(field.voxels()) * field.basis.size())
    throw InputError(what + ": " + std::to_string(field.weights.size()) + " element weights for " +
                     std::to_string(field.voxels()) + " voxels x " + std::to_string(field.basis.size()) + " matrices");
  for (double w : field.weights)
    if (!std::isfinite(w)) throw InputError(what + ": a non-finite element weight");
}

}  // namespace msfab
