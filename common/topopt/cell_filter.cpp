#include "topopt/cell_filter.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "core/errors.hpp"

namespace msfab {

CellFilter::CellFilter(const CellGrid& grid, const std::vector<std::int64_t>& design_cells, double radius) {
  using StorageIndex = Eigen::SparseMatrix<double, Eigen::RowMajor>::StorageIndex;
  const Eigen::Index n = Eigen::Index(design_cells.size());
  identity_ = radius <= 1.0;
  if (identity_) return;
  std::vector<std::int64_t> row_of(grid.cells(), -1);
  for (Eigen::Index r = 0; r < n; ++r) row_of[design_cells[r]] = r;
  // The cone as a list of offsets, k then j then i, so that each row's
  // columns come out sorted (cells are numbered i fastest, design rows in
  // cell order) and the compressed rows can be written in place: a 3D
  // filter of radius 5 has ~560 entries per row, and triplets plus Eigen's
  // sorting copy took three times the matrix (11 GB at 128x64x64).
  struct Offset {
    int di, dj, dk;
    double w;
  };
  std::vector<Offset> cone;
  const int reach = int(std::ceil(radius)) - 1, kz = grid.dimension() == 3 ? reach : 0;
  for (int dk = -kz; dk <= kz; ++dk)
    for (int dj = -reach; dj <= reach; ++dj)
      for (int di = -reach; di <= reach; ++di) {
        const double w = radius - std::sqrt(double(di * di + dj * dj + dk * dk));
        if (w > 0) cone.push_back({di, dj, dk, w});
      }
  // Calls f(column, weight) for every design cell in row r's cone.
  const auto for_each_neighbour = [&](Eigen::Index r, auto&& f) {
    const auto [i, j, k] = grid.cell_coords(design_cells[r]);
    for (const Offset& o : cone) {
      const int a = i + o.di, b = j + o.dj, c = k + o.dk;
      if (a < 0 || b < 0 || c < 0 || a >= grid.nx() || b >= grid.ny() || c >= grid.nz()) continue;
      const std::int64_t col = row_of[grid.cell_index(a, b, c)];
      if (col >= 0) f(col, o.w);
    }
  };
  std::vector<std::int64_t> start(n + 1, 0);
#pragma omp parallel for schedule(static)
  for (Eigen::Index r = 0; r < n; ++r) {
    std::int64_t count = 0;
    for_each_neighbour(r, [&](std::int64_t, double) { ++count; });
    start[r + 1] = count;
  }
  for (Eigen::Index r = 0; r < n; ++r) start[r + 1] += start[r];
  if (start[n] > std::int64_t(std::numeric_limits<StorageIndex>::max()))
    throw InputError("filter.radius " + std::to_string(radius) + " gives " + std::to_string(start[n]) +
                     " filter weights, more than a sparse matrix holds; use a smaller radius");
  H_.resize(n, n);
  H_.resizeNonZeros(Eigen::Index(start[n]));
  StorageIndex* outer = H_.outerIndexPtr();
  StorageIndex* inner = H_.innerIndexPtr();
  double* value = H_.valuePtr();
  for (Eigen::Index r = 0; r <= n; ++r) outer[r] = StorageIndex(start[r]);
#pragma omp parallel for schedule(static)
  for (Eigen::Index r = 0; r < n; ++r) {
    std::int64_t e = start[r];
    double total = 0;
    for_each_neighbour(r, [&](std::int64_t col, double w) {
      inner[e] = StorageIndex(col), value[e] = w, ++e;
      total += w;
    });
    for (e = start[r]; e < start[r + 1]; ++e) value[e] /= total;
  }
}

MatX CellFilter::apply(const MatX& q) const { return identity_ ? q : MatX(H_ * q); }

MatX CellFilter::apply_transpose(const MatX& g) const { return identity_ ? g : MatX(H_.transpose() * g); }

}  // namespace msfab
