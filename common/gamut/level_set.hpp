#pragma once
// The gamut as a level set (thesis §3.2.3): a signed distance Phi on a
// cell-centred Cartesian grid over the n-dimensional unit cube of
// normalized material properties, negative inside the achievable set.
//
//   1. Zhu-Bridson implicit function near the samples:
//      Phi(x) = |x - xbar(x)| - r, xbar the kernel-weighted mean of the
//      sample points within 2r (kernel (1 - s^2)^3, s = distance / 2r)
//   2. fast marching from the grid nodes next to the zero crossing, in
//      both directions, to a signed distance everywhere
//   3. a few explicit steps of dPhi/dt = Laplacian(Phi) (the thesis's
//      smoothing, §3.2.3)
//
// Queries are the multilinear interpolant and its exact gradient, so a
// gradient always matches finite differences of value(). The topology
// optimizer's per-cell constraint is value(p) <= 0.
#include <vector>

#include "core/types.hpp"

namespace msfab {

struct LevelSetOptions {
  int cells = 32;           // grid cells per axis
  double margin = 0.1;      // the grid covers [-margin, 1 + margin] per axis
  double radius = 0.0;      // r of the implicit function; 0: 1.5 grid cells
  int smoothing_steps = 2;  // explicit Laplacian steps (dt = h^2 / (4 d))
};

class GamutLevelSet {
 public:
  GamutLevelSet() = default;
  // Points (each of size d, 1 <= d <= 6) in the unit cube. InputError on
  // no points, mixed dimensions, a coordinate outside [0, 1], a grid of
  // more than 2^26 nodes, or bad options.
  static GamutLevelSet from_points(const std::vector<VecX>& points, const LevelSetOptions& options = {});

  // A level set from stored node values (an artifact): `values` has
  // cells^dimension entries, axis 0 fastest, node centres at
  // lower + (i + 1/2) spacing. InputError on a size mismatch.
  static GamutLevelSet from_values(int dimension, int cells, double lower, double spacing, std::vector<double> values,
                                   double padding = 0.0);

  int dimension() const { return dim_; }
  int cells() const { return cells_; }
  double spacing() const { return h_; }
  double lower() const { return lo_; }
  const std::vector<double>& values() const { return phi_; }  // axis 0 fastest
  // How far the zero level lies outside the samples: the radius r of the
  // implicit function (a single sample's Phi is -r). from_values() sets
  // it from its argument.
  double padding() const { return padding_; }
  // The same level set moved inward by `offset` (Phi + offset): with
  // offset = padding() its zero level runs through the outermost samples.
  GamutLevelSet shifted(double offset) const;

  // Multilinear interpolation of the node values; beyond the outermost
  // node centres the nearest in-range value plus the distance to it.
  double value(const VecX& p) const;
  // Gradient of that interpolant (inside the node range).
  VecX gradient(const VecX& p) const;
  // A C1 alternative for optimizers: the tensor-product quadratic B-spline
  // with the node values as coefficients (3^d nodes per query), and its
  // exact gradient. It reproduces linear functions, so a signed distance
  // keeps its slope; unlike value() its gradient has no jumps across grid
  // faces, which Newton-type optimizers need to settle on the boundary.
  // Beyond the node range: like value().
  double smooth_value(const VecX& p, VecX* gradient = nullptr) const;

 private:
  int dim_ = 0, cells_ = 0;
  double lo_ = 0, h_ = 0;
  double padding_ = 0;
  std::vector<double> phi_;
  std::vector<long long> stride_;
  double node(const std::vector<int>& index) const;
};

}  // namespace msfab
