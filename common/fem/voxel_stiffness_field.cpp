#include "fem/voxel_stiffness_field.hpp"

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

void validate_field(const VoxelStiffnessField& field, const std::string& what) {
  if (field.nx < 1 || field.ny < 1 || field.nz < 1) throw InputError(what + ": the cell has no voxels");
  if (!(field.h > 0) || !std::isfinite(field.h)) throw InputError(what + ": the voxel size must be > 0");
  if (field.basis.empty()) throw InputError(what + ": no element stiffness matrices");
  if (field.weights.size() != std::size_t(field.voxels()) * field.basis.size())
    throw InputError(what + ": " + std::to_string(field.weights.size()) + " element weights for " +
                     std::to_string(field.voxels()) + " voxels x " + std::to_string(field.basis.size()) +
                     " matrices");
  for (double w : field.weights)
    if (!std::isfinite(w)) throw InputError(what + ": a non-finite element weight");
}

}  // namespace msfab
