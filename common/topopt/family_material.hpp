#pragma once
// Cells made of one family's members (topopt space `family3d`): the cell's
// parameters are the family's own (beam half-sizes on the grid of
// msfab-family-generate `grid:`, normalized to [0, 1] per axis) and rho.
//
// A gamut level set around a handful of members is a thick blob in four
// properties: the optimizer may pick (E, nu, G, rho) far from every member,
// and what it prints then differs from what it designed. Here the cell's
// stiffness is the family's own, interpolated between neighbouring members
// (topopt/grid_interpolant.hpp), so every design point is on the family's
// two-parameter surface and at a grid node it is exactly that member's C^H.
//
// What is interpolated: the three eigenvalues of the cubic C^H
// (C11 + 2 C12, C11 - C12, C44), on a log scale, so C stays positive
// definite between members whose moduli differ by decades; and the solid
// fraction. rho stays a design parameter (the optimizers' mass terms read
// it) tied to the family by the constraint
//     Phi(p) = rho_family(t) - rho <= 0,
// which the mass terms keep active: a cell pays for the material its
// member has.
#include <memory>
#include <string>

#include "gamut/microstructure_set.hpp"
#include "topopt/cell_material.hpp"

namespace msfab {

// With `derived_density`, rho is not free: it is the family's solid
// fraction at the cell's parameters (CellMaterialModel::derives_density),
// and Phi is gone. This is the form a density filter on the parameters
// needs: a filtered cell is a mix of its neighbours' parameters, and a
// per-cell Phi on it would couple every cell to its neighbours.
//
// InputError naming `path` when the set has no parameter grid, is not a
// cubic3d set, or a member's C^H is not positive definite.
std::unique_ptr<CellMaterialModel> make_family_material_model(const MicrostructureSet& set, const std::string& path,
                                                              bool derived_density = false);

}  // namespace msfab
