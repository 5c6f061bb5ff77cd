#pragma once
// Density filter over the design cells of a grid (Bruns & Tortorelli 2001;
// the "ft = 2" filter of the 88-line code): a cell's physical parameters are
// the weighted mean of the design parameters of the cells within `radius`
// (in cell widths), with linear cone weights w = max(0, radius - distance).
// Filtering the parameters (rather than smoothing the gradient, as the
// thesis does) keeps the gradient exact, which Ipopt's line search needs;
// docs/topopt.md gives the reasoning. The filtered parameters are what the
// physics and the gamut constraint see.
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "topopt/cell_grid.hpp"

namespace msfab {

class CellFilter {
 public:
  CellFilter() = default;
  // `design_cells`: grid cell index of each design variable row. radius <= 1
  // gives the identity (no neighbour within the cone).
  CellFilter(const CellGrid& grid, const std::vector<std::int64_t>& design_cells, double radius);

  bool identity() const { return identity_; }
  // Rows: design cells; columns: parameters.
  MatX apply(const MatX& q) const;
  // Chain rule: gradient with respect to q of a function of p = apply(q).
  MatX apply_transpose(const MatX& gradient_p) const;
  // Row-normalized weights (design cells x design cells).
  const Eigen::SparseMatrix<double, Eigen::RowMajor>& weights() const { return H_; }

 private:
  bool identity_ = true;
  Eigen::SparseMatrix<double, Eigen::RowMajor> H_;
};

}  // namespace msfab
