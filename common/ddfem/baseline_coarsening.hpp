#pragma once
// The two baseline coarsenings DDFEM is compared with (thesis §2.5.2), as
// material lookups for build_coarse_mesh.
//
// Naive: every coarse quadrature point takes the material of the fine voxel
// it lies in (level 1: 2 x 2 x 2 Gauss points, one per child; level 2:
// 4 x 4 x 4 points, one per fine voxel). A point in a void voxel cannot get
// zero stiffness (Neo-Hookean needs mu > 0), so it takes the material of the
// nearest solid voxel of the block (Manhattan distance in voxels; ties go to
// the softer material, i.e. the smaller shear modulus, then the lower voxel
// index). Void is thus filled with the softest adjacent material, the
// smallest stiffness error this scheme can make.
//
// Averaged: one Neo-Hookean material per coarse element whose mu and lambda
// are the volume averages over all fine voxels of the block, void counting as
// mu = lambda = 0 (a half-void block is half as stiff).
//
// Palette: index = fine material id, [0] (void) unused; the Lame parameters
// are those reported by Material::shear_modulus() / lame_lambda().
#include <vector>

#include "ddfem/coarse_grid.hpp"

namespace msfab {

// Level 1: child ids are fine material ids.
CoarseMaterialLookup naive_coarsening(const std::vector<MaterialPtr>& palette);
CoarseMaterialLookup averaged_coarsening(const std::vector<MaterialPtr>& palette);

// Level 2: child ids are combinations of `level1` (index + 1, 0 = void),
// resolved to the 64 fine voxels of the block. Naive needs the 4-point rule
// (build_coarse_mesh's default at level 2).
CoarseMaterialLookup naive_coarsening(const std::vector<MaterialPtr>& palette, const CoarseGrid& level1);
CoarseMaterialLookup averaged_coarsening(const std::vector<MaterialPtr>& palette, const CoarseGrid& level1);

// Volume-averaged Lame parameters of the fine voxels in `fine_ids` (void = 0).
void average_lame(const std::vector<MaterialPtr>& palette, const std::vector<int>& fine_ids, double* mu,
                  double* lambda);

}  // namespace msfab
