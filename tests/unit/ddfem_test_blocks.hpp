#pragma once
// Blocks, palettes and fit options shared by the DDFEM unit tests.
#include <cmath>
#include <memory>
#include <random>
#include <vector>

#include "ddfem/coarse_fit.hpp"
#include "ddfem/fine_block.hpp"
#include "ddfem/force_samples.hpp"
#include "ddfem/periodic_samples.hpp"
#include "fem/hex8.hpp"
#include "material/neo_hookean.hpp"
#include "scene/scene.hpp"

namespace msfab::ddfem_test {

constexpr double kVoxel = 1e-3;

// A cantilever along y: the face y = 0 clamped, the face y = max loaded
// by `traction`.
inline void clamp_y0_load_top(Scene& s, const Vec3& traction) {
  BoundaryCondition clamp;
  clamp.where = "boundary[0]";
  clamp.region.kind = Region::Kind::Face;
  clamp.region.axis = 1;
  clamp.fix[0] = clamp.fix[1] = clamp.fix[2] = true;
  s.boundary.push_back(clamp);
  Load load;
  load.where = "loads[0]";
  load.region.kind = Region::Kind::Face;
  load.region.axis = 1;
  load.region.upper = true;
  load.value = traction;
  s.loads.push_back(load);
}

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

// A level-1 coarse material that is exactly NeoHookean(mu, lambda) at all 8
// points (its fine parameters too): the children of level-2 test blocks.
inline CoarseMaterialFit neo_hookean_level1(double mu, double lambda) {
  CoarseMaterialFit fit;
  fit.fitted = true;
  for (int k = 0; k < 8; ++k) fit.mu[k] = fit.mu0[k] = mu, fit.lambda[k] = fit.lambda0[k] = lambda;
  return fit;
}

// `count` samples of a known coarse material on the coarse element of
// `block`: random corner displacements of up to `amplitude` per component
// (the standardized mt19937_64 sequence of `seed`) and the material's
// energies. Fits on them must recover the material.
inline ForceSampleSet samples_of_coarse_material(const CoarseMaterialFit& truth, const FineBlock& block, int count,
                                                 double amplitude, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  const hex8::ElementGeometry geo = coarse_fit_geometry(X, truth.points(), truth.enhanced);
  ForceSampleSet set;
  set.patterns.resize(1);
  for (int i = 0; i < count; ++i) {
    ForceSample s;
    for (int j = 0; j < 24; ++j) s.corner_displacement[j] = amplitude * (2 * (double(rng() >> 11) * 0x1.0p-53) - 1);
    s.energy = coarse_energy(truth, geo, X, s.corner_displacement);
    set.samples.push_back(s);
  }
  return set;
}

// A homogeneous nearly incompressible (nu = 0.45) block, its periodic
// samples of every force family under small_fit_options() (with the
// anisotropic term off): the case where the trilinear element's locking
// shows most in a fit.
struct NearlyIncompressibleBlock {
  std::vector<MaterialPtr> palette = {nullptr, std::make_shared<NeoHookean>(1e6, 0.45)};
  FineBlock block = make_fine_block(BlockMaterials{1, 1, 1, 1, 1, 1, 1, 1}, palette, kVoxel);
  CoarseFitOptions options = [] {
    CoarseFitOptions o = small_fit_options();
    o.anisotropic = false;
    return o;
  }();
  ForceSampleSet samples = sample_periodic(block, options.sampling);
  std::vector<Vec3> directions = std::vector<Vec3>(8, Vec3::UnitX());
};

// A uniform draw in [0, 1) with 53 random bits.
inline double u01(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

// Corner positions X moved by the corner displacements u.
inline hex8::NodeMatrix deformed(const hex8::NodeMatrix& X, const Vec24& u) {
  hex8::NodeMatrix x = X;
  for (int c = 0; c < 8; ++c) x.row(c) += u.segment<3>(3 * c).transpose();
  return x;
}

}  // namespace msfab::ddfem_test
