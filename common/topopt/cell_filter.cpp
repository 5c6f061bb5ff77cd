#include "topopt/cell_filter.hpp"

#include <cmath>

namespace msfab {

CellFilter::CellFilter(const CellGrid& grid, const std::vector<std::int64_t>& design_cells, double radius) {
  const Eigen::Index n = Eigen::Index(design_cells.size());
  identity_ = radius <= 1.0;
  if (identity_) return;
  std::vector<std::int64_t> row_of(grid.cells(), -1);
  for (Eigen::Index r = 0; r < n; ++r) row_of[design_cells[r]] = r;
  const int reach = int(std::ceil(radius)) - 1, kz = grid.dimension() == 3 ? reach : 0;
  std::vector<Eigen::Triplet<double>> triplets;
  for (Eigen::Index r = 0; r < n; ++r) {
    const auto [i, j, k] = grid.cell_coords(design_cells[r]);
    double total = 0;
    const std::size_t first = triplets.size();
    for (int dk = -kz; dk <= kz; ++dk)
      for (int dj = -reach; dj <= reach; ++dj)
        for (int di = -reach; di <= reach; ++di) {
          const int a = i + di, b = j + dj, c = k + dk;
          if (a < 0 || b < 0 || c < 0 || a >= grid.nx() || b >= grid.ny() || c >= grid.nz()) continue;
          const std::int64_t col = row_of[grid.cell_index(a, b, c)];
          const double w = radius - std::sqrt(double(di * di + dj * dj + dk * dk));
          if (col < 0 || w <= 0) continue;
          triplets.emplace_back(int(r), int(col), w);
          total += w;
        }
    for (std::size_t t = first; t < triplets.size(); ++t)
      triplets[t] = Eigen::Triplet<double>(triplets[t].row(), triplets[t].col(), triplets[t].value() / total);
  }
  H_.resize(n, n);
  H_.setFromTriplets(triplets.begin(), triplets.end());
}

MatX CellFilter::apply(const MatX& q) const { return identity_ ? q : MatX(H_ * q); }

MatX CellFilter::apply_transpose(const MatX& g) const { return identity_ ? g : MatX(H_.transpose() * g); }

}  // namespace msfab
