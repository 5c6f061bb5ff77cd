#include "topopt/cell_grid.hpp"

#include <cmath>

#include "core/errors.hpp"

namespace msfab {

CellGrid::CellGrid(int dimension, int nx, int ny, int nz, double h) : dim_(dimension), n_{nx, ny, nz}, h_(h) {
  if (dimension != 2 && dimension != 3) throw InputError("grid: dimension must be 2 or 3");
  if (nx < 1 || ny < 1 || nz < 1) throw InputError("grid: every size must be >= 1");
  if (dimension == 2 && nz != 1) throw InputError("grid: a 2D grid has nz = 1");
  if (!(h > 0) || !std::isfinite(h)) throw InputError("grid: cell size must be > 0");
  const int m = voigt(), ne = element_unknowns();
  // 2-point Gauss per axis integrates the bilinear/trilinear stiffness exactly.
  const double g = 1.0 / std::sqrt(3.0);
  const double jac = std::pow(h / 2, dim_);
  const int points = dim_ == 3 ? 8 : 4;
  basis_.assign(voigt_pairs(), MatX::Zero(ne, ne));
  for (int q = 0; q < points; ++q) {
    Vec3 xi = Vec3::Zero();
    for (int a = 0; a < dim_; ++a) xi[a] = ((q >> (dim_ - 1 - a)) & 1) ? g : -g;
    const MatX B = strain_operator(xi);
    for (int s = 0; s < m; ++s)
      for (int t = s; t < m; ++t) {
        MatX term = B.row(s).transpose() * B.row(t);
        if (s != t) term += B.row(t).transpose() * B.row(s);
        basis_[pair_index(s, t, m)] += jac * term;
      }
  }
}

int CellGrid::pair_index(int s, int t, int m) {
  if (s > t) std::swap(s, t);
  return s * m - s * (s - 1) / 2 + (t - s);
}

std::int64_t CellGrid::nodes() const { return std::int64_t(n_[0] + 1) * (n_[1] + 1) * (dim_ == 3 ? n_[2] + 1 : 1); }

std::array<int, 3> CellGrid::cell_coords(std::int64_t c) const {
  return {int(c % n_[0]), int((c / n_[0]) % n_[1]), int(c / (std::int64_t(n_[0]) * n_[1]))};
}

std::array<int, 3> CellGrid::node_coords(std::int64_t n) const {
  const std::int64_t px = n_[0] + 1, py = n_[1] + 1;
  return {int(n % px), int((n / px) % py), int(n / (px * py))};
}

std::array<std::int64_t, 8> CellGrid::cell_nodes(std::int64_t c) const {
  const auto [i, j, k] = cell_coords(c);
  std::array<std::int64_t, 8> out{};
  for (int a = 0; a < corners(); ++a) {
    if (dim_ == 3)
      out[a] = node_index(i + (a >> 2 & 1), j + (a >> 1 & 1), k + (a & 1));
    else
      out[a] = node_index(i + (a >> 1 & 1), j + (a & 1), 0);
  }
  return out;
}

void CellGrid::cell_unknowns(std::int64_t c, std::int64_t* out) const {
  const auto nodes = cell_nodes(c);
  for (int a = 0; a < corners(); ++a)
    for (int d = 0; d < dim_; ++d) out[a * dim_ + d] = nodes[a] * dim_ + d;
}

Vec3 CellGrid::node_position(std::int64_t n) const {
  const auto [i, j, k] = node_coords(n);
  return Vec3(i, j, k) * h_;
}

Vec3 CellGrid::cell_center(std::int64_t c) const {
  const auto [i, j, k] = cell_coords(c);
  return Vec3(i + 0.5, j + 0.5, dim_ == 3 ? k + 0.5 : 0.0) * h_;
}

MatX CellGrid::strain_operator(const Vec3& xi) const {
  const int m = voigt(), nc = corners();
  MatX B = MatX::Zero(m, nc * dim_);
  for (int a = 0; a < nc; ++a) {
    Vec3 s = Vec3::Zero();  // corner sign per axis
    for (int d = 0; d < dim_; ++d) s[d] = ((a >> (dim_ - 1 - d)) & 1) ? 1.0 : -1.0;
    Vec3 grad = Vec3::Zero();  // dN_a/dx
    for (int d = 0; d < dim_; ++d) {
      double v = s[d] / 2;
      for (int e = 0; e < dim_; ++e)
        if (e != d) v *= (1 + s[e] * xi[e]) / 2;
      grad[d] = v * 2 / h_;
    }
    const int u = a * dim_;
    if (dim_ == 2) {
      B(0, u) = grad[0];
      B(1, u + 1) = grad[1];
      B(2, u) = grad[1], B(2, u + 1) = grad[0];
    } else {
      B(0, u) = grad[0];
      B(1, u + 1) = grad[1];
      B(2, u + 2) = grad[2];
      B(3, u + 1) = grad[2], B(3, u + 2) = grad[1];  // yz
      B(4, u) = grad[2], B(4, u + 2) = grad[0];      // xz
      B(5, u) = grad[1], B(5, u + 1) = grad[0];      // xy
    }
  }
  return B;
}

MatX CellGrid::center_strain_operator() const { return strain_operator(Vec3::Zero()); }

MatX CellGrid::element_stiffness(const MatX& C) const {
  const int m = voigt();
  MatX K = MatX::Zero(element_unknowns(), element_unknowns());
  for (int s = 0; s < m; ++s)
    for (int t = s; t < m; ++t) K += C(s, t) * basis_[pair_index(s, t, m)];
  return K;
}

}  // namespace msfab
