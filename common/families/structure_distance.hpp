#pragma once
// Geometric distance between periodic microstructures for family discovery
// (thesis §3.3.1): a smoothed Euclidean norm, minimized over the periodic
// translations of one cell against the other.
//
// A structure becomes a field first: its solid indicator (id != 0),
// optionally average-pooled to a coarser grid, then blurred with a
// periodic Gaussian. The blur is what makes the distance robust: two
// structures that differ by a one-voxel shift of a boundary are close,
// while the raw indicators would differ in a whole layer of voxels.
#include <array>
#include <vector>

#include "core/types.hpp"

namespace msfab {

// A scalar field on a periodic cubic cell of n x n x n voxels, x fastest:
// values[i + n * (j + n * k)].
struct VoxelField {
  int n = 0;
  VecX values;

  VoxelField() = default;
  explicit VoxelField(int n_, double fill = 0.0) : n(n_), values(VecX::Constant(Eigen::Index(n_) * n_ * n_, fill)) {}
  Eigen::Index index(int i, int j, int k) const {
    return Eigen::Index(i) + Eigen::Index(n) * (j + Eigen::Index(n) * k);
  }
  double& at(int i, int j, int k) { return values[index(i, j, k)]; }
  double at(int i, int j, int k) const { return values[index(i, j, k)]; }
};

// 1 where ids != 0, else 0. InputError unless ids.size() == n^3, n >= 1.
VoxelField solid_indicator(const std::vector<int>& ids, int n);

// Averages factor^3 blocks of voxels: an n^3 field becomes (n/factor)^3.
// InputError unless factor >= 1 divides n.
VoxelField average_pool(const VoxelField& field, int factor);

// Separable Gaussian blur with wrap-around; sigma in voxels of this field.
// The kernel is truncated at 4 sigma and normalized, so the total mass
// sum(values) is kept. sigma = 0 returns the field unchanged; InputError for
// a negative or non-finite sigma.
VoxelField periodic_gaussian_blur(const VoxelField& field, double sigma);

struct FieldOptions {
  int pool_factor = 1;  // average pooling before the blur (64^3 -> 32^3 with 2)
  double sigma = 1.0;   // blur width in voxels of the pooled grid
};
// The field compared by structure_distance: indicator, pooled, blurred.
VoxelField smoothed_field(const std::vector<int>& ids, int n, const FieldOptions& options = {});

// The periodic translate by `shift` voxels: out(x) = field(x - shift), so
// content at x moves to x + shift. Any integer shift is wrapped.
VoxelField translate_field(const VoxelField& field, const std::array<int, 3>& shift);

struct AlignedDistance {
  // min over translations t of sqrt(mean((a - translate_field(b, t))^2))
  double distance = 0.0;
  std::array<int, 3> shift{{0, 0, 0}};  // the minimizing t, each in [0, n)
};
// The translation is found from the FFT cross-correlation (O(N log N)); the
// distance is then summed directly at the best few candidate shifts, so a
// perfect match gives exactly 0 instead of FFT round-off. InputError when
// the fields differ in size or are empty.
AlignedDistance structure_distance(const VoxelField& a, const VoxelField& b);

// Symmetric matrix of structure_distance over all pairs, zero diagonal.
// Each field is transformed once; pairs run in parallel, each computed by
// the same serial code, so the result does not depend on the thread count.
// Memory: one half spectrum per field, (n/2 + 1) n^2 complex doubles:
// 0.28 MB at 32^3, 2.2 MB at 64^3.
MatX pairwise_structure_distances(const std::vector<VoxelField>& fields);

}  // namespace msfab
