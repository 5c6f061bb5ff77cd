#pragma once
// A 3 x 2 grid of synthetic cubic members for the family3d tests: denser
// and stiffer along the first axis, more anisotropic along the second.
#include <cmath>

#include "gamut/material_space.hpp"
#include "gamut/microstructure_set.hpp"

namespace msfab {

inline MicrostructureSet family_test_set() {
  MicrostructureSet set;
  set.space = "cubic3d";
  set.property_names = {"E", "nu", "G", "rho"};
  set.E_stiff = 1e6;
  set.decades = 4;
  set.nx = set.ny = set.nz = 2;
  set.stiff = {1e6, 0.3};
  set.grid.names = {"axis", "diagonal"};
  set.grid.axes = {{0.05, 0.2, 0.5}, {0.0, 0.1}};
  const MaterialSpace space(MaterialSpaceKind::cubic3d, set.E_stiff, set.decades);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 2; ++j) {
      Microstructure m;
      m.ids.assign(8, 1);
      const double rho = 0.1 + 0.35 * i + 0.05 * j;
      VecX raw(4);
      raw << 1e6 * std::pow(rho, 2.0), 0.1 + 0.08 * i + 0.05 * j, 1e6 * std::pow(rho, 2.0) * (0.3 + 0.2 * j), rho;
      m.C = space.tensor_3d(raw);
      m.properties = space.properties(m.C, rho);
      m.unit = space.normalize(m.properties);
      set.items.push_back(m);
    }
  return set;
}

}  // namespace msfab
