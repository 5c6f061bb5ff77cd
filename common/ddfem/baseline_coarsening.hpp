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
// Galerkin (not in the thesis; the coarse operator of geometric multigrid):
// every fine voxel integrated by its own 2 x 2 x 2 Gauss points over the
// coarse element's field (hex8::composite_gauss_rule(2^level, 2): 64 points
// at level 1, 512 at level 2), void voxels with no material. By default the
// element keeps only a subset of those points that integrates each
// material's stiffness exactly (ddfem/galerkin_quadrature.hpp: at most 23
// per material; "galerkin-full" keeps them all). The coarse
// element's energy is then exactly the fine mesh's energy of the coarse
// field interpolated to the fine nodes: each material sits where it is in
// the block, with its own lever arm in bending, where naive coarsening moves
// a child's stiffness to one Gauss point. Being a restriction of the fine
// model to the coarse space, it is stiffer than the fine model (it locks
// where the trilinear space locks); on the enhanced element the bubbles
// relax that.
//
// Homogenized (not in the thesis; a reference for what a coarse material
// can do): the block's voxels taken as a periodic cell and homogenized
// (homog/periodic_homogenization.hpp), and every quadrature point gets that
// C^H as an isotropic Neo-Hookean part t C_iso plus an anisotropic St.
// Venant-Kirchhoff part C^H - t C_iso (material/green_anisotropic.hpp), with
// C_iso the isotropic projection of C^H and t the largest factor that leaves
// the second part positive semidefinite. So the element's small-strain
// stiffness is exactly C^H, large rotations store no energy, and the
// Neo-Hookean part keeps it stable in compression. This is what periodic
// in-situ sampling of a block would converge to at small strain with a
// model that can represent any anisotropy. Blocks with void children are
// coarsened naively (a periodic cell of a partly-void block is not the
// block in a body).
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

// Galerkin: one material per point of hex8::composite_gauss_rule(2^level, 2),
// or, reduced, per point of the subset of it that keeps the small-strain
// stiffness (ddfem/galerkin_quadrature.hpp; the element carries that rule).
CoarseMaterialLookup galerkin_coarsening(const std::vector<MaterialPtr>& palette, bool reduced = true);
CoarseMaterialLookup galerkin_coarsening(const std::vector<MaterialPtr>& palette, const CoarseGrid& level1,
                                         bool reduced = true);

CoarseMaterialLookup homogenized_coarsening(const std::vector<MaterialPtr>& palette);
CoarseMaterialLookup homogenized_coarsening(const std::vector<MaterialPtr>& palette, const CoarseGrid& level1);

// Fine ids of a block laid out n x n x n, index (a * n + b) * n + c with a
// along x (slowest), the point order of hex8::gauss_rule(n): level 1 (the
// child ids) and level 2 (children are combinations of `level1`, index + 1,
// 0 = void).
std::vector<int> block_level1(const ChildIds& child);
std::vector<int> block_level2(const ChildIds& child, const std::vector<ChildIds>& level1);
// True for a block with no void voxel and more than one material: the blocks
// the matched model and the checked lookups act on.
bool solid_mixed_block(const std::vector<int>& ids);
// Naive materials of such a block on the n-point rule (one per voxel).
QuadratureMaterials naive_block(const std::vector<MaterialPtr>& palette, const std::vector<int>& ids, int n);
// C^H of the block taken as a periodic cell (material Voigt order).
Mat6 block_homogenized_stiffness(const std::vector<MaterialPtr>& palette, const std::vector<int>& ids, int n);

// The material the homogenized coarsening gives a block of stiffness C^H
// (Voigt order of material/voigt.hpp).
MaterialPtr homogenized_block_material(const Mat6& C);

// Volume-averaged Lame parameters of the fine voxels in `fine_ids` (void = 0).
void average_lame(const std::vector<MaterialPtr>& palette, const std::vector<int>& fine_ids, double* mu,
                  double* lambda);

}  // namespace msfab
