#pragma once
// Edge joints: two stiff cells that touch only along an edge (3D) or at a
// corner (2D), while both cells that would join them by faces are soft.
//
// A design made of such chains is a classic artefact of topology
// optimization (the checkerboard's 3D relative): the finite element model
// carries force through the shared edge nodes as if the joint had some
// width, but the printed joint is a line of material whose stiffness falls
// as the print gets finer. On a bridge designed in a lattice family the
// printed object was 21% softer than its homogenized model with 16^3
// voxels per cell and 32% with 32^3, where a design without such joints
// was 7% and 4% (docs/topopt.md, "Edge joints"). A density filter on the
// parameters prevents them; smoothing the gradient does not.
#include <cstdint>

#include "core/types.hpp"
#include "topopt/cell_grid.hpp"

namespace msfab {

struct EdgeJoints {
  std::int64_t count = 0;    // joints at or above the ratio
  double largest_ratio = 0;  // over every edge-sharing pair, 0 if none; 1e12 for void bridges
};

// A cell's stiffness is the mean of its normal Voigt diagonal (C11, C22 and
// C33; C11 and C22 in 2D), read from `pairs`: one row per grid cell, the
// upper triangle in CellGrid::pair_index order. A pair of cells that share
// an edge but no face is a joint when the softer of the two is at least
// `ratio` times stiffer than the stiffer of the two cells sharing a face
// with both. std::invalid_argument for a wrong shape or ratio <= 1.
EdgeJoints find_edge_joints(const CellGrid& grid, const MatX& pairs, double ratio = 10.0);

}  // namespace msfab
