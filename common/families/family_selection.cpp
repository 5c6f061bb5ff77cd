#include "families/family_selection.hpp"

#include "core/errors.hpp"

namespace msfab {

double shear_modulus_ratio(double E, double nu, double G) { return 2.0 * G * (1.0 + nu) / E; }

std::vector<std::int64_t> select_structures(const MicrostructureSet& set, const SelectionOptions& options,
                                            const GamutLevelSet* gamut, const std::string& set_path) {
  if (set.space != "cubic3d")
    throw InputError(set_path + ": attribute 'space' is '" + set.space +
                     "'; family discovery needs a 3D cubic set (space cubic3d)");
  if (set.nx != set.ny || set.ny != set.nz || set.nx < 4)
    throw InputError(set_path + ": cells of " + std::to_string(set.nx) + " x " + std::to_string(set.ny) + " x " +
                     std::to_string(set.nz) + " voxels; family discovery needs cubic cells of at least 4^3");
  const PropertyWindow& w = options.window;
  std::vector<std::int64_t> kept;
  for (std::size_t s = 0; s < set.items.size(); ++s) {
    const Microstructure& m = set.items[s];
    // cubic3d order: E, nu, G, rho (gamut/material_space.hpp).
    const double E = m.properties[0] / set.E_stiff, nu = m.properties[1], rho = m.properties[3];
    if (!(nu >= w.nu_min && nu <= w.nu_max && E >= w.E_min && E <= w.E_max && rho >= w.density_min &&
          rho <= w.density_max))
      continue;
    if (gamut && options.boundary_margin >= 0 && gamut->value(m.unit) < -options.boundary_margin) continue;
    kept.push_back(std::int64_t(s));
  }
  return kept;
}

}  // namespace msfab
