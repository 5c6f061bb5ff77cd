#pragma once
// Matched coarsening (not in the thesis; docs/ddfem.md, "Matched
// materials"): naive materials carried onto the block's effective stiffness.
//
// Naive coarsening keeps where in a block each material sits (every coarse
// point takes the material of its fine voxel), so the element has the right
// lever arms in bending; but its response to a uniform strain is the points'
// weighted mean (Voigt), far too stiff across a laminate or a fibre. The
// homogenized baseline has the right uniform response, the block's periodic
// C^H, but one material everywhere, and loses the lever arms (fibres: worse
// than naive). Matched coarsening keeps both. The points' small-strain
// stiffnesses C_q are carried by one congruence
//   C_q' = S C_q S,   S symmetric positive definite,
// chosen so that the element's response to uniform strains is exactly C^H.
// On the trilinear element that response is the weighted mean A of the C_q,
// and S is the unique SPD solution of S A S = C^H,
//   S = A^-1/2 (A^1/2 C^H A^1/2)^1/2 A^-1/2;
// on the enhanced element the bubbles relax a heterogeneous element below
// its mean, so S is refined by a fixed-point iteration on the condensed
// element's response. A homogeneous block keeps its material (S = I).
// Each C_q' becomes a material as in homogenized coarsening
// (homogenized_block_material: a Neo-Hookean part and an anisotropic
// St. Venant-Kirchhoff part; rotation invariant). Blocks with void are
// coarsened naively: a periodic cell of a partly void block is not that
// block in a body.
#include <vector>

#include "ddfem/coarse_fit.hpp"
#include "ddfem/coarse_grid.hpp"
#include "fem/hex_element.hpp"

namespace msfab {

// The matched small-strain stiffnesses (material Voigt order) of the points
// of an n x n x n block (fine ids in the layout of block_level1, no void)
// on the n-point Gauss rule of the unit coarse element, trilinear or with
// bubble modes. `iterations` receives the fixed-point steps taken, and
// `residual` the final ||A - C^H|| / ||C^H|| of the element's response.
std::vector<Mat6> matched_point_stiffness(const std::vector<MaterialPtr>& palette, const std::vector<int>& ids, int n,
                                          bool enhanced, int* iterations = nullptr, double* residual = nullptr);

// An element's response to uniform strains at rest, A = U^T K U / V (K its
// stiffness with any bubble modes condensed, U the corner displacements of
// the six unit Voigt strains): the 6 x 6 stiffness it shows a uniform strain
// field (material Voigt order), for small-strain stiffnesses C per point of
// `geo`. Computed from the points directly (the bubbles' 9 x 9 condensation),
// not by assembling K: tested against the assembled element.
Mat6 uniform_strain_response(const hex8::ElementGeometry& geo, const std::vector<Mat6>& C);
// The same for per-point small-strain stiffnesses `C` on the n-point rule
// of the unit cube.
Mat6 element_uniform_response(const std::vector<Mat6>& C, int n, bool enhanced);

// How far apart two stiffnesses are, independent of units and of the basis
// of strains: the root mean square of log(lambda_i) over the generalized
// eigenvalues of A v = lambda B v (0 for A = B; 0.1: about 10% too stiff or
// too soft on average over the six strain modes). A and B must be SPD.
double stiffness_distance(const Mat6& A, const Mat6& B);

// A database fit's response to uniform strains on the element it was fitted
// for (uniform_strain_response of its materials).
Mat6 fit_uniform_response(const CoarseMaterialFit& fit);

// Small-strain stiffness of a material at rest (material Voigt order).
Mat6 rest_voigt_stiffness(const Material& material);

// Per-point stiffnesses C carried by one congruence (the fixed point above)
// until the element's uniform response (geometry `geo`) is `target`.
std::vector<Mat6> congruent_to_response(std::vector<Mat6> C, const hex8::ElementGeometry& geo, const Mat6& target,
                                        int* iterations = nullptr, double* residual = nullptr);

// Matched materials of one block (fine ids laid out as block_level1, n per
// edge) carried onto `target` instead of the block's C^H; naive materials
// for a block with void or of one material.
QuadratureMaterials matched_block_materials(const std::vector<MaterialPtr>& palette, const std::vector<int>& ids, int n,
                                            bool enhanced, const Mat6* target = nullptr);

// The stiffness of solid cell `cell` of `cells` (fine ids `ids`, laid out as
// block_level1, n = cells.fine_per_cell() per edge) among `margin` voxels of
// its real neighbours (windowed_stiffness); where the window does not
// determine one, the cell's own C^H, and *unresolved is set.
Mat6 cell_windowed_stiffness(const VoxelGrid& fine, const std::vector<MaterialPtr>& palette, const CoarseGrid& cells,
                             const std::vector<int>& ids, int cell, int margin, bool* unresolved);

// Windowed matched coarsening (`--coarse-window M`): the matched materials
// of cell `cell` of `cells` (level 1 or 2 of `fine`; `level1` its level-1
// grid at level 2, else null) carried onto its windowed_stiffness with
// `margin` voxels of its real neighbours; naive materials for a cell with
// void or of one material. Where the window does not determine a
// stiffness, the cell's own C^H is used and *unresolved set.
QuadratureMaterials windowed_matched_cell(const VoxelGrid& fine, const std::vector<MaterialPtr>& palette,
                                          const CoarseGrid& cells, const CoarseGrid* level1, bool enhanced, int margin,
                                          int cell, bool* unresolved);

// Lookups for build_coarse_mesh: level 1 (children are fine ids) and level 2
// (children are combinations of `level1`). `enhanced`: the coarse element
// the mesh is built with.
CoarseMaterialLookup matched_coarsening(const std::vector<MaterialPtr>& palette, bool enhanced);
CoarseMaterialLookup matched_coarsening(const std::vector<MaterialPtr>& palette, const CoarseGrid& level1,
                                        bool enhanced);

}  // namespace msfab
