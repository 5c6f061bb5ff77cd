#include "topopt/edge_joints.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <stdexcept>
#include <vector>

namespace msfab {
namespace {
// Bridges of no stiffness at all (void) give this ratio instead of infinity.
constexpr double kVoidBridge = 1e-12;
}  // namespace

EdgeJoints find_edge_joints(const CellGrid& grid, const MatX& pairs, double ratio) {
  const int dim = grid.dimension(), m = grid.voigt();
  if (pairs.rows() != grid.cells() || pairs.cols() != grid.voigt_pairs())
    throw std::invalid_argument("find_edge_joints: one row of Voigt pairs per cell expected");
  if (!(ratio > 1)) throw std::invalid_argument("find_edge_joints: the ratio must be > 1");
  std::vector<double> stiffness(std::size_t(grid.cells()));
  for (std::int64_t c = 0; c < grid.cells(); ++c) {
    double s = 0;
    for (int a = 0; a < dim; ++a) s += pairs(c, CellGrid::pair_index(a, a, m));
    stiffness[std::size_t(c)] = s / dim;
  }
  const std::array<int, 3> n{grid.nx(), grid.ny(), grid.nz()};
  const auto at = [&](std::array<int, 3> x) { return stiffness[std::size_t(grid.cell_index(x[0], x[1], x[2]))]; };
  EdgeJoints joints;
  // Each unordered pair once: the first axis always steps forward, the
  // second forward or back.
  for (int a = 0; a < dim; ++a)
    for (int b = a + 1; b < dim; ++b)
      for (int sign : {1, -1})
        for (int k = 0; k < n[2]; ++k)
          for (int j = 0; j < n[1]; ++j)
            for (int i = 0; i < n[0]; ++i) {
              const std::array<int, 3> x{i, j, k};
              std::array<int, 3> y = x, bridge1 = x, bridge2 = x;
              y[a] += 1, y[b] += sign;
              if (y[a] >= n[a] || y[b] < 0 || y[b] >= n[b]) continue;
              bridge1[a] += 1, bridge2[b] += sign;
              const double pair = std::min(at(x), at(y));
              const double bridges = std::max(at(bridge1), at(bridge2));
              if (!(pair > 0)) continue;
              const double r = pair / std::max(bridges, kVoidBridge * pair);
              joints.largest_ratio = std::max(joints.largest_ratio, r);
              if (r >= ratio) ++joints.count;
            }
  return joints;
}

}  // namespace msfab
