#pragma once
// The Galerkin coarse element on fewer points (ddfem/baseline_coarsening.hpp).
//
// The Galerkin element integrates every fine voxel of its block by the
// voxel's own 2 x 2 x 2 Gauss points: 64 points at level 1, 512 at level 2,
// so it costs about what the fine elements it replaces cost. Its small-strain
// stiffness is sum_m integral over the voxels of material m of
// (grad phi_a)^T C_m (grad phi_b), with phi the trilinear shape functions and
// the element's bubbles 1 - chi_k^2: on the cube [-1, 1]^3 each such integral
// is a combination of the integrals of 23 monomials chi^a (a in {0,1,2}^3,
// the products of two shape-function gradients) over the material's voxels.
// A point set that integrates those 23 monomials over each material's voxels
// exactly therefore gives the same small-strain stiffness, bit for bit up to
// round-off, and at finite strain the same energy to the quadrature error of
// a smooth integrand. Such a set is found among the composite rule's own
// points by non-negative least squares (the empirical cubature of
// hyper-reduction): the basic solution has at most 23 points per material
// with weights >= 0 (so every point's energy still counts with its sign and
// inversion is still seen at the points kept).
#include <array>
#include <vector>

#include "fem/hex8.hpp"

namespace msfab {

// The exponents (a, b, c) of the monomials chi_1^a chi_2^b chi_3^c spanned by
// the products of two gradient components of the trilinear shape functions
// and bubbles 1 - chi_k^2 on [-1, 1]^3: 23 of the 27 with exponents <= 2.
std::vector<std::array<int, 3>> hex_stiffness_monomials();

struct ReducedRule {
  hex8::QuadratureRule rule;
  std::vector<int> source;  // the index in the full rule of each point kept
};

// Points of `full` grouped by `group` (group[q] < 0: the point is dropped):
// per group, a subset of its points whose non-negative weights integrate
// every stiffness monomial over the group as `full` does (relative residual
// <= 1e-11). A group the non-negative least squares cannot reduce to that
// accuracy keeps all its points. Kept points are in the order of `full`.
ReducedRule reduced_stiffness_rule(const hex8::QuadratureRule& full, const std::vector<int>& group);

}  // namespace msfab
