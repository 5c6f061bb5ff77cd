#pragma once
// Blocks, palettes and fit options shared by the DDFEM unit tests.
#include <memory>
#include <vector>

#include "ddfem/coarse_fit.hpp"
#include "ddfem/fine_block.hpp"
#include "material/neo_hookean.hpp"

namespace msfab::ddfem_test {

constexpr double kVoxel = 1e-3;

// Ids 1 (soft) and 2 (stiff), nu = 0.3; id 0 is void.
inline std::vector<MaterialPtr> two_materials(double E_soft, double E_stiff) {
  return {nullptr, std::make_shared<NeoHookean>(E_soft, 0.3), std::make_shared<NeoHookean>(E_stiff, 0.3)};
}

// Soft children below z = h, stiff above: layers normal to z (1-voxel
// layers when the block is repeated periodically).
inline BlockMaterials layered_ids() {
  BlockMaterials ids;
  for (int c = 0; c < 8; ++c) ids[c] = (c & 1) ? 2 : 1;
  return ids;
}

// A small sampling: axes + 1 direction, 2 magnitudes, 10 stretching directions.
inline CoarseFitOptions small_fit_options() {
  CoarseFitOptions o;
  o.sampling.sphere_directions = 1;
  o.sampling.magnitudes = 2;
  o.anisotropy.directions = 10;
  return o;
}

}  // namespace msfab::ddfem_test
