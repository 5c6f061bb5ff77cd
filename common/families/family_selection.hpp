#pragma once
// Which structures of a gamut take part in family discovery (thesis §3.3):
// a window in the property space (e.g. the auxetic structures, ν < 0, or
// those with ν > 0.3) and, optionally, only those near the gamut boundary,
// where the extremal families live.
#include <cstdint>
#include <string>
#include <vector>

#include "gamut/level_set.hpp"
#include "gamut/microstructure_set.hpp"

namespace msfab {

struct PropertyWindow {
  double nu_min = -1.0, nu_max = 0.5;  // Poisson's ratio
  double E_min = 0.0, E_max = 1.0;     // Young's modulus relative to the stiff material
  double density_min = 0.0, density_max = 1.0;
};

struct SelectionOptions {
  PropertyWindow window;
  // With a gamut level set: keep structures with Phi >= -boundary_margin
  // (unit-cube distance inside the boundary). Negative: no boundary filter.
  double boundary_margin = -1.0;
};

// The shear modulus ratio G' = 2 G (1 + ν) / E (thesis Eq. 3.10): 1 for an
// isotropic material.
double shear_modulus_ratio(double E, double nu, double G);

// Indices (ascending) of the cubic3d structures of `set` inside the window
// (and near the boundary of `gamut` when it is given and the margin >= 0).
// InputError when the set is not a 3D cubic set of cubic cells.
std::vector<std::int64_t> select_structures(const MicrostructureSet& set, const SelectionOptions& options,
                                            const GamutLevelSet* gamut, const std::string& set_path);

}  // namespace msfab
