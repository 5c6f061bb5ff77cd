#pragma once
// A cell's stiffness among its actual neighbours (docs/ddfem.md, "Windowed
// stiffness"). The block's periodic C^H takes its neighbours to be copies
// of itself: an oblique fibre crossing the block is cut by its periodic
// images, and a random block among random neighbours is softer than among
// its copies. Here the cell and `margin` voxels of its real neighbours (the
// grid mirrored at its faces) are homogenized periodically, and the cell's
// apparent stiffness is read from the cell alone: under the six load cases
// the cell's mean strains E (6 x 6, one column per case) and its energies
// W_mn = sum over the cell's voxels of u_m^T K u_n / V_cell, so that
//   A = E^-T W E^-1
// stores the cell's energy for the cell's mean strain in every case. With
// margin 0 the window is the cell, E = I and A = C^H.
#include <vector>

#include "fem/voxel_grid.hpp"

namespace msfab {

// The n^3 cell whose first voxel is (i0, j0, k0) of `fine` (material Voigt
// order). InputError if the cell has a void voxel; NumericalError if the
// window holds void (the body's free surface, which a periodic window turns
// into a crack) or the cell's mean strains do not determine A.
Mat6 windowed_stiffness(const VoxelGrid& fine, const std::vector<MaterialPtr>& palette, int i0, int j0, int k0, int n,
                        int margin);

// The window of that cell: the (n + 2 margin)^3 voxel ids, the grid mirrored
// at its faces, x slowest. Cells with equal windows have equal windowed
// stiffnesses.
std::vector<int> cell_window(const VoxelGrid& fine, int i0, int j0, int k0, int n, int margin);

}  // namespace msfab
