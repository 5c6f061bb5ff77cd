#pragma once
// The discrete step's move (thesis §3.2.1): a structure is changed by adding
// or subtracting a few beams of random sizes, then made cubic (square)
// symmetric and cleaned. Deterministic in its seed.
#include <cstdint>

#include "fem/voxel_grid.hpp"
#include "gamut/structure_ops.hpp"

namespace msfab {

struct BeamMoveOptions {
  int max_beams = 3;        // 1..max_beams beams per move
  double min_radius = 0.5;  // beam radius range, voxels
  double max_radius = 2.0;
  int materials = 1;  // added beams take a solid id in 1..materials
  int cut_id = 0;     // what a cut leaves: void, or the soft base material
  CellSymmetry symmetry = CellSymmetry::cubic;
};

// A new structure from `cell` (cubic n x n x n or square n x n x 1 for
// cubic symmetry): each beam joins two random points of the cell and
// either adds a random solid id or cuts to `cut_id` (equal odds); then
// mirror_fundamental_domain and clean_structure. Returns an all-void cell if the clean-up leaves nothing.
VoxelGrid evolve_structure(const VoxelGrid& cell, std::uint64_t seed, const BeamMoveOptions& options = {});

}  // namespace msfab
