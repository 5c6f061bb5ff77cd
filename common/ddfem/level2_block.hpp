#pragma once
// The block a level-2 coarse material is fitted to (thesis §2.3.5 / §2.5):
// 2 x 2 x 2 level-1 coarse elements, each carrying its fitted level-1
// material (8 Gauss points), coarsened into one element with the 4-point
// Gauss rule (64 points, one in each fine voxel of the 4 x 4 x 4 voxels the
// element covers). Sampling and fitting run on it unchanged: its "fine"
// mesh is again 2 x 2 x 2 hexahedra.
#include <array>

#include "ddfem/coarse_fit.hpp"

namespace msfab {

// `children[c]` is the level-1 fit of child c (hex8 order), fitted and with
// 8 points; `child_size` the level-1 element edge (2 fine voxels). `ids`
// labels the block (e.g. the children's level-1 entry indices + 1). Eq.
// 2.9's p^0 at each of the 64 points: the palette material of the fine
// voxel the point lies in (the child's own p^0 at its level-1 point in that
// voxel), not the child's fitted parameters, which are a poor prior: a
// level-1 fit often moves its stiffness between points and parameters
// (docs/ddfem.md, "Level 2"). A null child is void (ids[c] must then
// be 0): no element there, p^0 = 0 at its points, as a void voxel in a
// level-1 block. Throws InputError on an unfitted child, a child with
// another point count, or no child at all. `context`: layers of periodic
// copies around the block, in level-1 elements (see make_fine_block).
FineBlock make_block_of_coarse_materials(const std::array<const CoarseMaterialFit*, 8>& children,
                                         const BlockMaterials& ids, double child_size, int context = 0);

// The 4 x 4 x 4 palette ids (x fastest, as make_voxel_block takes them) of
// a level-2 block whose child c is the level-1 block `children[c]` (its
// material_ids are palette ids; null: a void child).
std::vector<int> level2_voxel_ids(const std::array<const CoarseMaterialFit*, 8>& children);

// Level-1 point of child `child` that lies in the same fine voxel as point
// q of the 4-point rule (both in hex8 bit order).
int level1_point_of(int q, int* child);

}  // namespace msfab
