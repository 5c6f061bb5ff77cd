#pragma once
// Which voxels of a full-resolution model carry unknowns (thesis §3.6).
//
// A printed object is its solid voxels; void carries nothing. Modelling
// void as an ersatz material (1e-6 of the stiff one) keeps every node in
// the system but makes it ill-conditioned by that ratio, and a voxel model
// that is mostly void then spends most of its CG iterations on the void.
// Removing void instead leaves two things to decide, both here:
//
//  * pieces: solid voxels sharing a face belong to one piece. Pieces that
//    touch only along an edge or at a corner are a hinge in a hexahedral
//    model (and barely connected when printed), so they are separate.
//  * held: a piece is held when the fixed unknowns on its nodes prevent all
//    six rigid motions. A piece that is not held has a singular stiffness
//    (it floats, or turns about a support line or point): it is removed and
//    reported, since its displacement would be set by the ersatz void alone.
//
// Nodes that no remaining solid voxel touches carry no stiffness; the
// caller fixes them at zero (fix_unknowns_without_material), which keeps the
// grid's numbering for the matrix-free multigrid.
#include <cstdint>
#include <vector>

#include "topopt/cell_grid.hpp"

namespace msfab {

struct SolidPieces {
  std::vector<int> piece;          // per cell of the grid: its piece, -1 for void
  std::vector<std::int64_t> size;  // per piece: its cells
  int count() const { return static_cast<int>(size.size()); }
};

// Face-connected components of the solid cells (one flag per cell of a 3D
// grid), numbered in the order of their first cell (deterministic).
SolidPieces face_connected_pieces(const CellGrid& grid, const std::vector<char>& solid);

// Per piece: how many independent rigid motions (0..6) the fixed unknowns
// (one flag per unknown) on its nodes prevent. 6 means held.
std::vector<int> restrained_rigid_motions(const CellGrid& grid, const SolidPieces& pieces,
                                          const std::vector<char>& fixed);

struct PieceRemoval {
  int pieces = 0;                  // face-connected pieces before removal
  int removed = 0;                 // of those, not held and removed
  std::int64_t removed_cells = 0;  // solid cells removed with them
  std::int64_t kept_cells = 0;     // solid cells left
};
// Sets the cells of every piece that is not held to void.
PieceRemoval remove_unheld_pieces(const CellGrid& grid, std::vector<char>& solid, const std::vector<char>& fixed);

// Fixes every unknown of a node no solid cell touches (`node_material`, one
// flag per node). Returns how many nodes that fixed.
std::int64_t fix_unknowns_without_material(const CellGrid& grid, const std::vector<char>& node_material,
                                           std::vector<char>& fixed);

// Per node: 1 when a solid cell touches it.
std::vector<char> solid_nodes(const CellGrid& grid, const std::vector<char>& solid);

}  // namespace msfab
