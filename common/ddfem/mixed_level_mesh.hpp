#pragma once
// A mesh that mixes coarsening levels (adaptive coarsening, docs/ddfem.md
// "Adaptive coarsening"): every level-2 cell (4 x 4 x 4 fine voxels) is
// meshed at the level chosen for it, as its solid fine voxels (level 0), its
// level-1 coarse elements (level 1) or its one level-2 coarse element
// (level 2), with the same materials the uniform models use.
//
// All nodes lie on the fine node lattice. Where a smaller element meets a
// larger one, the small element's nodes on the large element's face or edge
// are hanging: they are not unknowns but the trilinear interpolation of the
// large element's corners (NodeConstraints of fem/elastic_assembler.hpp), so
// the displacement stays continuous across the interface. A hanging node is
// interpolated in the largest element it hangs on, and a corner of that
// element that hangs itself is replaced by its own interpolation, so every
// hanging node ends up as a combination of unknown nodes.
#include <array>
#include <memory>
#include <vector>

#include "ddfem/coarse_grid.hpp"
#include "fem/elastic_assembler.hpp"
#include "scene/scene.hpp"

namespace msfab {

struct MixedLevelMesh {
  HexMesh mesh;
  std::shared_ptr<const NodeConstraints> constraints;
  // The lattice of fine nodes, padded to whole level-2 cells:
  // 4 * level2.n + 1 points per axis, x fastest.
  std::array<int, 3> lattice{};
  std::vector<int> node_lattice;   // mesh node -> lattice index
  std::vector<int> unknown_node;   // unknown node -> mesh node
  std::vector<int> element_level;  // per element: 0, 1 or 2
  // Per fine voxel of the scene grid: the element whose box holds it (-1
  // where that is none, i.e. a void voxel of a level-0 cell).
  std::vector<int> voxel_element;
  std::array<int, 3> elements_per_level{};
  int hanging_nodes = 0;

  int num_unknown_nodes() const { return static_cast<int>(unknown_node.size()); }
};

// `cell_level` has one entry (0, 1 or 2) per cell of `level2`, which must be
// coarsen_grid(level1) with level1 = coarsen_grid(fine). The lookups give
// the materials of level-1 and level-2 cells as for build_coarse_mesh (one per
// Gauss point, with the centre, or the Galerkin element's 8 per fine voxel).
// enhanced_modes: level-1 and level-2 elements carry the condensed bubble
// modes of hex8::enhanced_element_geometry. The bubbles are element-internal
// (incompatible) modes, so the hanging-node constraints act on the trilinear
// part, as the coarse-to-fine interpolation of a uniform enhanced model does.
// Throws InputError on mismatched grids or levels.
MixedLevelMesh build_mixed_level_mesh(const VoxelGrid& fine, const std::vector<MaterialPtr>& palette,
                                      const CoarseGrid& level1, const CoarseGrid& level2,
                                      const std::vector<int>& cell_level, const CoarseMaterialLookup& level1_materials,
                                      const CoarseMaterialLookup& level2_materials, bool enhanced_modes = false);

// Displacements (or positions) of the unknowns interpolated to the fine
// mesh's nodes: a (fine nodes) x (unknown nodes) matrix with rows summing to
// 1. Each fine node is interpolated in the element holding one of its solid
// voxels.
SpMat mixed_to_fine_interpolation(const VoxelGrid& fine_grid, const VoxelMesh& fine_mesh, const MixedLevelMesh& mixed);

// A start for Newton on a model whose nodes lie on the fine node lattice (a
// mixed-level mesh, or a uniform model of a finer level): the displacements
// of a uniform coarse solution (`x_coarse`, positions of `coarse_mesh`'s
// nodes) at `points` (rest positions), 3 per point. Each point is
// interpolated trilinearly in a coarse element whose cell touches it, or
// extrapolated from the nearest cell with an element where every cell
// around it is void. A starting guess, not a model: the caller solves from it.
VecX uniform_displacement_at(const CoarseGrid& grid, const VoxelMesh& coarse_mesh, const VecX& x_coarse,
                             const NodeArray& points);

// The scene's conditions on the unknowns. Forces: the fine nodal forces
// restricted by the transpose of mixed_to_fine_interpolation (total force
// and moment kept). Dirichlet conditions: a node is fixed where the fine,
// level-1 or level-2 model that has a node at its place fixes it (regions are
// geometric, so these agree). Hanging nodes carry no condition of their own;
// `unresolved` (if given) receives the level-2 cells that hold a hanging
// node the fine model fixes while one of its interpolation corners is free,
// so that the caller can refine them.
StaticConditions mixed_static_conditions(const Scene& scene, const VoxelMesh& fine_mesh,
                                         const StaticConditions& fine_conditions, const CoarseGrid& level1,
                                         const CoarseGrid& level2, const MixedLevelMesh& mixed,
                                         std::vector<int>* unresolved = nullptr);

}  // namespace msfab
