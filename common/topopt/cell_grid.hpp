#pragma once
// The regular grid of cells a topology optimization works on (thesis §3.4):
// nx x ny (x nz) square or cubic cells of edge h, one bilinear quad (2D) or
// trilinear hexahedron (3D) per cell, `dimension` displacement unknowns per
// node.
//
// Numbering: cell i + nx (j + ny k); node i + (nx+1) (j + (ny+1) k); unknown
// dimension * node + component. A cell's corner a sits at offset
// (a>>2&1, a>>1&1, a&1) in 3D (the hex8 order of Table 2.1) and
// (a>>1&1, a&1) in 2D.
//
// The element stiffness is linear in the cell's Voigt stiffness C
// (order xx, yy, xy in 2D; xx, yy, zz, yz, xz, xy in 3D, engineering shears,
// as in homog/elastic_tensor.hpp): K_e(C) = sum_{s<=t} C_st B_st with
// B_ss = int B_s^T B_s and B_st = int (B_s^T B_t + B_t^T B_s). A 2D grid is
// a plate of unit thickness (energies per unit thickness).
#include <array>
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace msfab {

class CellGrid {
 public:
  CellGrid() = default;
  // InputError for a dimension other than 2 or 3, a non-positive size, nz
  // != 1 in 2D, or h <= 0.
  CellGrid(int dimension, int nx, int ny, int nz, double h);

  int dimension() const { return dim_; }
  int nx() const { return n_[0]; }
  int ny() const { return n_[1]; }
  int nz() const { return n_[2]; }
  double h() const { return h_; }
  std::int64_t cells() const { return std::int64_t(n_[0]) * n_[1] * n_[2]; }
  std::int64_t nodes() const;
  std::int64_t unknowns() const { return nodes() * dim_; }
  int corners() const { return dim_ == 3 ? 8 : 4; }
  int element_unknowns() const { return corners() * dim_; }
  // Voigt size: 3 in 2D, 6 in 3D; and the number of upper-triangle entries.
  int voigt() const { return dim_ == 3 ? 6 : 3; }
  int voigt_pairs() const { return voigt() * (voigt() + 1) / 2; }

  std::int64_t node_index(int i, int j, int k) const {
    return i + std::int64_t(n_[0] + 1) * (j + std::int64_t(n_[1] + 1) * k);
  }
  std::int64_t cell_index(int i, int j, int k) const { return i + std::int64_t(n_[0]) * (j + std::int64_t(n_[1]) * k); }
  std::array<int, 3> cell_coords(std::int64_t c) const;
  std::array<int, 3> node_coords(std::int64_t n) const;
  // The corner nodes of a cell in element order.
  std::array<std::int64_t, 8> cell_nodes(std::int64_t c) const;
  // The element's unknowns, corner by corner.
  void cell_unknowns(std::int64_t c, std::int64_t* out) const;
  Vec3 node_position(std::int64_t n) const;
  Vec3 cell_center(std::int64_t c) const;
  double cell_volume() const { return dim_ == 3 ? h_ * h_ * h_ : h_ * h_; }

  // The element basis B_st, pair index of (s, t), s <= t, row-major over
  // the upper triangle: (0,0), (0,1), ..., (0,m-1), (1,1), ...
  const std::vector<MatX>& element_basis() const { return basis_; }
  static int pair_index(int s, int t, int m);
  // K_e for a Voigt stiffness (m x m, symmetric).
  MatX element_stiffness(const MatX& C) const;
  // The strain-displacement rows at the cell centre (m x element unknowns),
  // for stress and energy-density output.
  MatX center_strain_operator() const;

 private:
  int dim_ = 0;
  std::array<int, 3> n_{0, 0, 0};
  double h_ = 1.0;
  std::vector<MatX> basis_;
  MatX strain_operator(const Vec3& xi) const;  // at natural coordinates in [-1, 1]
};

}  // namespace msfab
