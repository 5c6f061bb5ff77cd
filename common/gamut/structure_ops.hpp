#pragma once
// Editing microstructure cells for the gamut sampler (thesis §3.2.1):
// cubic symmetry by mirroring the fundamental domain, random beams, and the
// clean-up that keeps a structure printable and load-bearing.
//
// A cell with nz = 1 is 2D: its symmetry is the square's (8 elements), and
// connectivity and wrapping are in the plane.
#include <array>
#include <cstdint>
#include <vector>

#include "fem/voxel_grid.hpp"

namespace msfab {

// cubic: the 48 (2D: 8) symmetries of the cube (square), for cubic
// materials; orthotropic: the mirror planes through the cell centre
// normal to each axis (8; 2D: 4), for orthotropic materials.
enum class CellSymmetry { cubic, orthotropic };

// The voxel of the fundamental domain that symmetry maps voxel (i, j, k)
// onto: each index folded onto the lower half (min(i, n - 1 - i)), then,
// for cubic symmetry, the folded indices sorted (3D; 2D sorts i, j and
// keeps k = 0). A cubic cell must be cubic (nx = ny = nz) or square
// (nx = ny, nz = 1).
std::array<int, 3> fundamental_voxel(const VoxelGrid& cell, int i, int j, int k,
                                     CellSymmetry symmetry = CellSymmetry::cubic);

// Copies every voxel from its fundamental-domain voxel, making the cell
// invariant under the symmetry group. InputError for a cubic symmetry on a
// cell that is neither cubic nor square.
void mirror_fundamental_domain(VoxelGrid& cell, CellSymmetry symmetry = CellSymmetry::cubic);
bool has_cubic_symmetry(const VoxelGrid& cell);
bool has_symmetry(const VoxelGrid& cell, CellSymmetry symmetry);

// Sets to `id` every voxel whose centre lies within `radius` of the
// segment a-b (cell coordinates: voxel units, voxel (i, j, k) centred at
// (i + 0.5, j + 0.5, k + 0.5)). Returns the number of voxels changed.
int paint_beam(VoxelGrid& cell, const Vec3& a, const Vec3& b, double radius, int id);

// A face connector: per voxel, 1 for the voxels within `depth` layers of a
// cell face whose other coordinates lie in the face's central square of
// half-width `half_width` voxels (2D: the central segment of each edge).
// Invariant under the cubic and orthotropic symmetries; two cells carrying
// it meet across every shared face on the same solid patch. InputError for
// a cell that is not cubic/square, half_width < 1, depth < 1, or a patch
// wider than the face.
std::vector<std::uint8_t> face_connector(const VoxelGrid& cell, int half_width, int depth);

// The axis backbone: the beams along x, y (and z) through the cell centre,
// 2 * half_width voxels wide (their central indices, as face_connector's
// patches), painted solid (id 1), and every solid voxel that is not
// face-connected to them inside the cell (not through the periodic
// boundary: across a face a mapped cell meets another structure) removed.
// Two cells that carry it meet at every shared face centre, whatever else
// they hold, and each cell is one piece. A cubic (orthotropic) cell stays
// cubic (orthotropic).
// Returns the voxels changed; InputError as face_connector.
int add_axis_backbone(VoxelGrid& cell, int half_width);

struct CleanupReport {
  int removed_voxels = 0;  // solid voxels in pieces that do not wrap around the cell
  int filled_voxels = 0;   // void voxels in enclosed cavities
};
// Keeps only the solid pieces (face-connected) that wrap around the
// periodic cell along every axis (the load-bearing network), and in 3D
// fills enclosed void pieces (void that does not wrap along any axis: it
// would trap support material) with the most frequent solid id around
// them. A 2D cell keeps its holes.
CleanupReport clean_structure(VoxelGrid& cell);

// The printer's minimum feature size, in voxels: the voxels (solid or
// void) that no width^d window (periodic; 2D: width x width x 1) entirely
// of their own phase covers, i.e. what a morphological opening of the
// solid or of the void with that window would change. 0 for width <= 1.
// A beam or a gap thinner than `width` voxels shows up here; a two-material
// cell is all solid, so only its void is checked.
std::int64_t thin_feature_voxels(const VoxelGrid& cell, int width);

}  // namespace msfab
