#include "solve/node_lattice.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "core/errors.hpp"

namespace msfab {

namespace {

[[noreturn]] void not_a_lattice(const std::string& why) { throw InputError("pcg-mg needs a voxel mesh: " + why); }

std::string format_point(const NodePositions& positions, Eigen::Index node) {
  char text[96];
  std::snprintf(text, sizeof(text), "(%.9g, %.9g, %.9g)", positions(node, 0), positions(node, 1), positions(node, 2));
  return text;
}

// Smallest gap between distinct values, distinct meaning further apart than
// tolerance; 0 if all values coincide.
double smallest_gap(std::vector<double> values, double tolerance) {
  std::sort(values.begin(), values.end());
  double gap = 0.0;
  for (std::size_t i = 1; i < values.size(); ++i) {
    const double step = values[i] - values[i - 1];
    if (step > tolerance && (gap == 0.0 || step < gap)) gap = step;
  }
  return gap;
}

}  // namespace

NodeLattice lattice_from_positions(const NodePositions& positions) {
  const Eigen::Index n = positions.rows();
  if (n == 0) not_a_lattice("node_positions has no nodes");
  if (!positions.allFinite()) not_a_lattice("node_positions holds a non-finite coordinate");

  const Eigen::RowVector3d low = positions.colwise().minCoeff();
  const Eigen::RowVector3d high = positions.colwise().maxCoeff();
  const double extent = std::max((high - low).maxCoeff(), low.cwiseAbs().maxCoeff());
  // Rounding in the positions of a voxel mesh is far below this.
  const double tolerance = 1e-9 * std::max(extent, 1e-300);
  std::array<double, 3> spacing{1.0, 1.0, 1.0};
  NodeLattice lattice;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> values(static_cast<std::size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i) values[i] = positions(i, axis);
    const double gap = smallest_gap(std::move(values), tolerance);
    if (gap > 0.0) spacing[axis] = gap;
    const double points = std::round((high[axis] - low[axis]) / spacing[axis]) + 1.0;
    lattice.dims[axis] = static_cast<int>(std::min(points, 2e9));
  }
  const double lattice_points = double(lattice.dims[0]) * double(lattice.dims[1]) * double(lattice.dims[2]);
  // A voxel mesh fills a good part of its bounding box; a scattered point
  // set would make the dense point -> node map (and the hierarchy) useless.
  if (lattice_points > 64.0 * double(n) + 1e6) {
    not_a_lattice("the " + std::to_string(n) + " nodes would need a lattice of " + std::to_string(lattice.dims[0]) +
                  " x " + std::to_string(lattice.dims[1]) + " x " + std::to_string(lattice.dims[2]) +
                  " points (their smallest coordinate gaps are not a common spacing)");
  }

  lattice.coords.resize(static_cast<std::size_t>(n));
  lattice.node_at.assign(static_cast<std::size_t>(lattice_points), -1);
  for (Eigen::Index node = 0; node < n; ++node) {
    std::array<int, 3>& c = lattice.coords[node];
    for (int axis = 0; axis < 3; ++axis) {
      const double t = (positions(node, axis) - low[axis]) / spacing[axis];
      const double rounded = std::round(t);
      if (std::abs(t - rounded) > 1e-6) {
        not_a_lattice("node " + std::to_string(node) + " at " + format_point(positions, node) +
                      " is off the regular lattice of spacing (" + std::to_string(spacing[0]) + ", " +
                      std::to_string(spacing[1]) + ", " + std::to_string(spacing[2]) + ")");
      }
      c[axis] = static_cast<int>(rounded);
    }
    const std::size_t point = static_cast<std::size_t>(c[0]) +
                              static_cast<std::size_t>(lattice.dims[0]) *
                                  (static_cast<std::size_t>(c[1]) + static_cast<std::size_t>(lattice.dims[1]) * c[2]);
    int& slot = lattice.node_at[point];
    if (slot >= 0) {
      not_a_lattice("nodes " + std::to_string(slot) + " and " + std::to_string(node) + " share the position " +
                    format_point(positions, node));
    }
    slot = static_cast<int>(node);
  }
  return lattice;
}

namespace {

// Numbers the points of `lattice` marked in node_at (>= 0) in lattice
// order, x fastest, and lists their coordinates.
void number_marked_points(NodeLattice& lattice) {
  std::size_t point = 0;
  for (int k = 0; k < lattice.dims[2]; ++k) {
    for (int j = 0; j < lattice.dims[1]; ++j) {
      for (int i = 0; i < lattice.dims[0]; ++i, ++point) {
        int& slot = lattice.node_at[point];
        if (slot < 0) continue;
        slot = lattice.num_nodes();
        lattice.coords.push_back({i, j, k});
      }
    }
  }
}

}  // namespace

NodeLattice coarsen_lattice(const NodeLattice& fine) {
  NodeLattice coarse;
  for (int axis = 0; axis < 3; ++axis) {
    // Fine coordinate m needs coarse points floor(m/2) and ceil(m/2).
    coarse.dims[axis] = fine.dims[axis] / 2 + 1;
  }
  const std::size_t points = static_cast<std::size_t>(coarse.dims[0]) * coarse.dims[1] * coarse.dims[2];
  coarse.node_at.assign(points, -1);
  auto point_index = [&](int i, int j, int k) {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(coarse.dims[0]) *
               (static_cast<std::size_t>(j) + static_cast<std::size_t>(coarse.dims[1]) * k);
  };
  for (const std::array<int, 3>& c : fine.coords) {
    // Coarse points within one fine spacing: c/2 for even c, else both neighbours.
    for (int k = c[2] / 2; k <= (c[2] + 1) / 2; ++k) {
      for (int j = c[1] / 2; j <= (c[1] + 1) / 2; ++j) {
        for (int i = c[0] / 2; i <= (c[0] + 1) / 2; ++i) coarse.node_at[point_index(i, j, k)] = 0;
      }
    }
  }
  number_marked_points(coarse);
  return coarse;
}

NodeLattice coarsen_lattice_by_injection(const NodeLattice& fine) {
  NodeLattice coarse;
  for (int axis = 0; axis < 3; ++axis) coarse.dims[axis] = fine.dims[axis] / 2 + 1;
  coarse.node_at.assign(static_cast<std::size_t>(coarse.dims[0]) * coarse.dims[1] * coarse.dims[2], -1);
  auto point_index = [&](int i, int j, int k) {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(coarse.dims[0]) *
               (static_cast<std::size_t>(j) + static_cast<std::size_t>(coarse.dims[1]) * k);
  };
  auto injected = [&](int i, int j, int k) { return fine.node(2 * i, 2 * j, 2 * k) >= 0; };
  for (const std::array<int, 3>& c : fine.coords) {
    bool has_parent = false;
    for (int k = c[2] / 2; k <= (c[2] + 1) / 2; ++k)
      for (int j = c[1] / 2; j <= (c[1] + 1) / 2; ++j)
        for (int i = c[0] / 2; i <= (c[0] + 1) / 2; ++i)
          if (injected(i, j, k)) {
            coarse.node_at[point_index(i, j, k)] = 0;
            has_parent = true;
          }
    if (!has_parent) coarse.node_at[point_index(c[0] / 2, c[1] / 2, c[2] / 2)] = 0;
  }
  number_marked_points(coarse);
  return coarse;
}

}  // namespace msfab
