#pragma once
// Online coarsening of a voxel grid (thesis §2.4): every 2 x 2 x 2 block of
// fine voxels becomes one coarse hexahedron whose quadrature-point materials
// are looked up from the material ids of its 8 children.
//
// Child order: child (di, dj, dk) of a block has index 4*di + 2*dj + dk, the
// bit order of hex8 nodes and of the points of hex8::gauss_rule(2), so
// quadrature point q of a level-1 element lies inside child q.
//
// Odd grid sizes are padded with void on the upper side of each axis, so the
// coarse grid has ceil(n / 2) cells per axis and may reach half a coarse
// cell beyond the fine grid. A block whose 8 children are all void is no
// element.
//
// Level 2 (4 x 4 x 4 fine voxels per element) applies the same block
// structure to the level-1 grid whose "material ids" are its child-id
// combinations (index + 1, 0 = void): the children of a level-2 cell are
// level-1 combinations, exactly the keys of a level-2 material database.
#include <array>
#include <functional>
#include <vector>

#include "fem/voxel_grid.hpp"
#include "scene/scene.hpp"

namespace msfab {

using ChildIds = std::array<int, 8>;

struct CoarseGrid {
  int level = 1;                              // fine voxels per coarse edge: 2^level
  int nx = 0, ny = 0, nz = 0;                 // coarse cells per axis
  int fine_nx = 0, fine_ny = 0, fine_nz = 0;  // the original voxel grid
  double fine_voxel_size = 0;
  double cell_size = 0;  // 2^level * fine voxel size
  Vec3 origin = Vec3::Zero();
  // Per cell (x fastest): index into `combinations`, -1 for an all-void block.
  std::vector<int> cell_combination;
  // Distinct child-id combinations in order of first appearance. Level 1:
  // fine voxel material ids (0 = void). Level 2: level-1 combination index
  // + 1 (0 = an all-void level-1 child).
  std::vector<ChildIds> combinations;
  double seconds = 0;  // wall time spent building this grid

  size_t index(int i, int j, int k) const { return size_t(i) + size_t(nx) * (size_t(j) + size_t(ny) * k); }
  // The first fine voxel (i, j, k) of cell c: the inverse of index, times 2^level.
  std::array<int, 3> first_voxel(int c) const {
    const int n = fine_per_cell();
    return {n * (c % nx), n * ((c / nx) % ny), n * (c / (nx * ny))};
  }
  int fine_per_cell() const { return 1 << level; }
  int num_cells() const { return nx * ny * nz; }
  int num_elements() const;
  // The grid of coarse cells as a voxel grid: voxel size cell_size, id =
  // combination index + 1 (0 where the block is void). Scene regions and
  // build_static_conditions work on it unchanged.
  VoxelGrid as_voxel_grid() const;
};

// Level 1 from a voxel grid. Throws InputError for an empty or invalid grid.
CoarseGrid coarsen_grid(const VoxelGrid& fine);
// One level further: level 2 from a level-1 grid.
CoarseGrid coarsen_grid(const CoarseGrid& coarse);

// The materials of a coarse element from its children's ids (a database
// lookup, or one of the baselines of baseline_coarsening.hpp). Must return
// one material, or one per quadrature point of the coarse rule.
using CoarseMaterialLookup = std::function<QuadratureMaterials(const ChildIds& child_ids)>;

// The materials of combination c of the grid (for lookups that need more
// than the child ids, e.g. the cell's neighbours on a grid with one
// combination per cell).
using IndexedMaterialLookup = std::function<QuadratureMaterials(int combination)>;

// The same grid with every solid cell its own combination (its child ids),
// numbered in cell order: materials per cell instead of per distinct block.
CoarseGrid with_one_combination_per_cell(const CoarseGrid& grid);

struct CoarseMeshStats {
  int elements = 0;
  int distinct_combinations = 0;  // lookups made (one per distinct combination)
  double seconds = 0;             // mesh build including the lookups
};

// The coarse hex mesh, built like build_voxel_mesh on as_voxel_grid(): shared
// nodes in lattice order, colours by cell parity, one geometry with
// points_per_axis Gauss points (0: 2 at level 1, 4 at level 2). Elements with
// the same child combination share one QuadratureMaterials entry; element_tag
// is combination index + 1. `element_voxel` / `voxel_element` of the result
// index coarse cells.
// enhanced_modes: elements with the three condensed bubble modes of
// hex8::enhanced_element_geometry (no bending locking), for every material.
// An element's rule follows its number of materials: 1 or one per Gauss
// point, one more with the centre point (ddfem/coarse_fit.hpp), or 8 per
// fine voxel for hex8::composite_gauss_rule(fine_per_cell(), 2) (the
// Galerkin element, ddfem/baseline_coarsening.hpp), so lookups may mix them.
VoxelMesh build_coarse_mesh(const CoarseGrid& grid, const CoarseMaterialLookup& lookup, int points_per_axis = 0,
                            CoarseMeshStats* stats = nullptr, bool enhanced_modes = false);
VoxelMesh build_coarse_mesh(const CoarseGrid& grid, const IndexedMaterialLookup& lookup, int points_per_axis = 0,
                            CoarseMeshStats* stats = nullptr, bool enhanced_modes = false);

// Trilinear interpolation from coarse nodes to fine nodes as an
// (fine nodes) x (coarse nodes) matrix; rows sum to 1. Each fine node is
// interpolated in the coarse element holding one of its solid voxels.
// Throws InputError if `coarse` was not built from `fine_grid`.
SpMat coarse_to_fine_interpolation(const VoxelGrid& fine_grid, const VoxelMesh& fine_mesh, const CoarseGrid& coarse,
                                   const VoxelMesh& coarse_mesh);

// The scene's conditions on the coarse mesh. Dirichlet conditions: the
// scene's regions evaluated on the coarse grid (face and box regions are
// geometric; a box must contain coarse nodes, and an upper face of an odd,
// padded axis moves to the padded boundary). Forces: the fine nodal forces
// (loads and gravity) restricted by the transpose of the interpolation, which
// keeps their total force and moment.
StaticConditions coarse_static_conditions(const Scene& fine_scene, const VoxelMesh& fine_mesh, const CoarseGrid& coarse,
                                          const VoxelMesh& coarse_mesh);

}  // namespace msfab
