#pragma once
// Directions of anisotropy of a fine block (thesis §2.3.3): the block is
// stretched along directions spread over a sphere, and at each coarse
// quadrature point the stretch l = ||F v|| of the stretching direction v is
// recorded; the principal axes of the point cloud {l v} follow from an SVD.
//
// Returned per point: the axis of LEAST stretch (smallest singular value),
// i.e. the stiffest direction. The spring of Eq. 2.7 can only add
// stiffness, so it belongs where the block is stiffer than an isotropic
// coarse point would be (in-plane for a layered block).
#include <array>
#include <cstdint>
#include <vector>

#include "ddfem/fine_block.hpp"

namespace msfab {

struct AnisotropyOptions {
  int directions = 24;   // stretching directions on a hemisphere (+-v give the same)
  double strain = 0.05;  // linear peak strain of the most compliant direction
  std::uint64_t seed = 7;
  double newton_tolerance = 1e-9;
};

struct AnisotropyEstimate {
  std::vector<Vec3> direction;        // unit, per coarse quadrature point
  std::vector<Vec3> singular_values;  // of the point cloud, descending
  int solves = 0;
  int dropped = 0;  // stretching solves that did not converge
};

// Deformation gradient at each coarse quadrature point for corner
// displacements u (24, node-major).
std::vector<Mat3> coarse_deformation_gradients(const hex8::ElementGeometry& coarse, const hex8::NodeMatrix& X,
                                               const Vec24& u);

// A spring direction's canonical sign (v and -v are the same spring): the
// largest component positive.
Vec3 canonical_direction(const Vec3& v);

// Requires a block with all corners (std::invalid_argument otherwise).
AnisotropyEstimate estimate_anisotropy(const FineBlock& block, const AnisotropyOptions& options);

}  // namespace msfab
