#include "verify/solid_pieces.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <stdexcept>

#include "core/errors.hpp"

namespace msfab {
namespace {

void require_3d(const CellGrid& grid, const char* what) {
  if (grid.dimension() != 3) throw std::invalid_argument(std::string(what) + ": a 3D grid");
}

}  // namespace

SolidPieces face_connected_pieces(const CellGrid& grid, const std::vector<char>& solid) {
  require_3d(grid, "face_connected_pieces");
  if (std::int64_t(solid.size()) != grid.cells())
    throw std::invalid_argument("face_connected_pieces: one flag per cell");
  const int n[3] = {grid.nx(), grid.ny(), grid.nz()};
  SolidPieces out;
  out.piece.assign(solid.size(), -1);
  std::vector<std::int64_t> queue;
  for (std::int64_t seed = 0; seed < grid.cells(); ++seed) {
    if (!solid[std::size_t(seed)] || out.piece[std::size_t(seed)] >= 0) continue;
    const int label = out.count();
    queue.assign(1, seed);
    out.piece[std::size_t(seed)] = label;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const auto c = grid.cell_coords(queue[head]);
      for (int axis = 0; axis < 3; ++axis)
        for (int step : {-1, 1}) {
          int q[3] = {c[0], c[1], c[2]};
          q[axis] += step;
          if (q[axis] < 0 || q[axis] >= n[axis]) continue;
          const std::int64_t next = grid.cell_index(q[0], q[1], q[2]);
          if (!solid[std::size_t(next)] || out.piece[std::size_t(next)] >= 0) continue;
          out.piece[std::size_t(next)] = label;
          queue.push_back(next);
        }
    }
    out.size.push_back(std::int64_t(queue.size()));
  }
  return out;
}

std::vector<int> restrained_rigid_motions(const CellGrid& grid, const SolidPieces& pieces,
                                          const std::vector<char>& fixed) {
  require_3d(grid, "restrained_rigid_motions");
  if (std::int64_t(fixed.size()) != grid.unknowns())
    throw std::invalid_argument("restrained_rigid_motions: one flag per unknown");
  const int count = pieces.count();
  // Rotations about each piece's box centre, lengths in its largest extent:
  // translations and rotations then weigh alike in the rank test.
  std::vector<Vec3> low(std::size_t(count), Vec3::Constant(1e300)), high(std::size_t(count), Vec3::Constant(-1e300));
  for (std::int64_t c = 0; c < grid.cells(); ++c)
    if (const int p = pieces.piece[std::size_t(c)]; p >= 0) {
      const auto q = grid.cell_coords(c);
      const Vec3 x(q[0], q[1], q[2]);
      low[std::size_t(p)] = low[std::size_t(p)].cwiseMin(x);
      high[std::size_t(p)] = high[std::size_t(p)].cwiseMax(x + Vec3::Ones());
    }
  std::vector<Eigen::Matrix<double, 6, 6>> gram(std::size_t(count), Eigen::Matrix<double, 6, 6>::Zero());
  const int n[3] = {grid.nx(), grid.ny(), grid.nz()};
  int touching[8];
  for (std::int64_t node = 0; node < grid.nodes(); ++node) {
    const bool any_fixed =
        fixed[std::size_t(3 * node)] || fixed[std::size_t(3 * node + 1)] || fixed[std::size_t(3 * node + 2)];
    if (!any_fixed) continue;
    const auto v = grid.node_coords(node);
    int distinct = 0;
    for (int a = 0; a < 8; ++a) {
      const int i = v[0] - (a & 1), j = v[1] - (a >> 1 & 1), k = v[2] - (a >> 2 & 1);
      if (i < 0 || j < 0 || k < 0 || i >= n[0] || j >= n[1] || k >= n[2]) continue;
      const int p = pieces.piece[std::size_t(grid.cell_index(i, j, k))];
      if (p >= 0 && std::find(touching, touching + distinct, p) == touching + distinct) touching[distinct++] = p;
    }
    for (int t = 0; t < distinct; ++t) {
      const std::size_t p = std::size_t(touching[t]);
      const double extent = std::max((high[p] - low[p]).maxCoeff(), 1.0);
      const Vec3 y = (Vec3(v[0], v[1], v[2]) - 0.5 * (low[p] + high[p])) / extent;
      for (int d = 0; d < 3; ++d) {
        if (!fixed[std::size_t(3 * node + d)]) continue;
        Eigen::Matrix<double, 6, 1> row = Eigen::Matrix<double, 6, 1>::Zero();
        row[d] = 1.0;
        for (int k = 0; k < 3; ++k) row[3 + k] = Vec3::Unit(k).cross(y)[d];
        gram[p].noalias() += row * row.transpose();
      }
    }
  }
  std::vector<int> rank(std::size_t(count), 0);
  for (int p = 0; p < count; ++p) {
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(gram[std::size_t(p)]);
    const auto& lambda = eig.eigenvalues();
    const double largest = lambda.maxCoeff();
    if (!(largest > 0)) continue;
    for (int k = 0; k < 6; ++k)
      if (lambda[k] > 1e-9 * largest) ++rank[std::size_t(p)];
  }
  return rank;
}

PieceRemoval remove_unheld_pieces(const CellGrid& grid, std::vector<char>& solid, const std::vector<char>& fixed) {
  const SolidPieces pieces = face_connected_pieces(grid, solid);
  const std::vector<int> rank = restrained_rigid_motions(grid, pieces, fixed);
  PieceRemoval out;
  out.pieces = pieces.count();
  std::vector<char> remove(std::size_t(pieces.count()), 0);
  for (int p = 0; p < pieces.count(); ++p)
    if (rank[std::size_t(p)] < 6) {
      remove[std::size_t(p)] = 1;
      ++out.removed;
      out.removed_cells += pieces.size[std::size_t(p)];
    } else {
      out.kept_cells += pieces.size[std::size_t(p)];
    }
  for (std::size_t c = 0; c < solid.size(); ++c)
    if (const int p = pieces.piece[c]; p >= 0 && remove[std::size_t(p)]) solid[c] = 0;
  return out;
}

std::vector<char> solid_nodes(const CellGrid& grid, const std::vector<char>& solid) {
  require_3d(grid, "solid_nodes");
  if (std::int64_t(solid.size()) != grid.cells()) throw std::invalid_argument("solid_nodes: one flag per cell");
  std::vector<char> out(std::size_t(grid.nodes()), 0);
  const int n[3] = {grid.nx(), grid.ny(), grid.nz()};
#pragma omp parallel for schedule(static)
  for (std::int64_t node = 0; node < grid.nodes(); ++node) {
    const auto p = grid.node_coords(node);
    char any = 0;
    for (int a = 0; a < 8 && !any; ++a) {
      const int i = p[0] - (a & 1), j = p[1] - (a >> 1 & 1), k = p[2] - (a >> 2 & 1);
      if (i >= 0 && j >= 0 && k >= 0 && i < n[0] && j < n[1] && k < n[2])
        any = solid[std::size_t(grid.cell_index(i, j, k))] ? 1 : 0;
    }
    out[std::size_t(node)] = any;
  }
  return out;
}

std::int64_t fix_unknowns_without_material(const CellGrid& grid, const std::vector<char>& node_material,
                                           std::vector<char>& fixed) {
  if (std::int64_t(node_material.size()) != grid.nodes() || std::int64_t(fixed.size()) != grid.unknowns())
    throw std::invalid_argument("fix_unknowns_without_material: one flag per node and per unknown");
  const int dim = grid.dimension();
  std::int64_t count = 0;
  for (std::int64_t node = 0; node < grid.nodes(); ++node)
    if (!node_material[std::size_t(node)]) {
      ++count;
      for (int d = 0; d < dim; ++d) fixed[std::size_t(dim * node + d)] = 1;
    }
  return count;
}

}  // namespace msfab
