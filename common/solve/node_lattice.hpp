#pragma once
// Nodes that sit on a regular lattice: the nodes of a voxel mesh, and every
// level of the geometric multigrid hierarchy built on them. A lattice may
// have holes (void voxels); only the points that carry a node are listed.
#include <array>
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace msfab {

// Rest positions, one row per node (the layout of NodeArray in fem/hex_mesh.hpp).
using NodePositions = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

struct NodeLattice {
  std::array<int, 3> dims{0, 0, 0};        // lattice points per axis
  std::vector<std::array<int, 3>> coords;  // node -> integer lattice coordinates
  std::vector<int> node_at;                // lattice point (x fastest) -> node, or -1

  int num_nodes() const { return static_cast<int>(coords.size()); }
  // The node at lattice point (i, j, k); -1 if the point is outside or empty.
  int node(int i, int j, int k) const {
    if (i < 0 || j < 0 || k < 0 || i >= dims[0] || j >= dims[1] || k >= dims[2]) return -1;
    return node_at[static_cast<std::size_t>(i) +
                   static_cast<std::size_t>(dims[0]) *
                       (static_cast<std::size_t>(j) + static_cast<std::size_t>(dims[1]) * k)];
  }
};

// Finds the lattice the positions lie on: per axis, the origin is the
// smallest coordinate and the spacing the smallest gap between distinct
// coordinates. Node order is kept (it need not be lattice order). Throws
// InputError ("pcg-mg needs a voxel mesh: ...") if a node is off the
// lattice, two nodes share a point, a coordinate is not finite, or the
// lattice would be far larger than the node count.
NodeLattice lattice_from_positions(const NodePositions& positions);

// The next coarser level: lattice points with even coordinates, halved. A
// coarse point gets a node if some fine node lies within one fine spacing of
// it on every axis (inside the support of its trilinear hat function).
// Coarse nodes are numbered in lattice order (x fastest).
NodeLattice coarsen_lattice(const NodeLattice& fine);

// The next coarser level of a mesh of mixed element sizes: the lattice
// points with even coordinates whose fine point holds a node, plus, for a
// fine node none of whose enclosing coarse corners is such a point, the
// corner at floor(c / 2). Where large elements leave nodes at odd
// coordinates with no node beside them, coarsen_lattice would give each two
// coarse points that only it reaches, and P^T A P would be singular; here
// every coarse point has a fine node of its own (GridTransfer's parents
// follow this rule). Numbered in lattice order (x fastest).
NodeLattice coarsen_lattice_by_injection(const NodeLattice& fine);

}  // namespace msfab
