#pragma once
// Scoring and resampling of the sampler's particle population (thesis
// §3.2.1, Eq. 3.1-3.2, after SOSMC): particles near the gamut boundary and
// in under-sampled regions are kept and evolved.
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace msfab {

// Eq. 3.2: D(p) = sum_k (1 - |p - p_k|^2 / h^2)^4 over the samples p_k
// within the support radius h (the thesis: a tenth of the level-set
// lattice's extent).
double sample_density(const VecX& p, const std::vector<VecX>& samples, double h);

// Eq. 3.1 as we read it: s = b(Phi) / D * 1 / D. The thesis writes Phi for
// the first factor and says it "favors microstructures near the gamut
// boundary"; a signed distance is negative inside, so we use the boundary
// weight b = max(0, 1 - |Phi| / depth): 1 on the boundary, 0 at `depth`
// from it on either side. D >= 1 for a particle that is itself a sample.
double particle_score(double phi, double density, double depth);

// Systematic resampling (Douc et al. 2005): `count` indices drawn with
// probabilities proportional to `weights` (>= 0, not all zero) from one
// uniform offset u0 in [0, 1): index i appears floor(count w_i) or
// ceil(count w_i) times. InputError on bad weights.
std::vector<int> systematic_resample(const std::vector<double>& weights, int count, double u0);

}  // namespace msfab
