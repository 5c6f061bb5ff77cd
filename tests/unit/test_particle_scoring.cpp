// Sampler scoring (Eq. 3.1-3.2) and systematic resampling.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/errors.hpp"
#include "gamut/particle_scoring.hpp"

namespace msfab {
namespace {

TEST(ParticleScoring, DensityKernelAndScore) {
  const std::vector<VecX> samples = {VecX::Constant(2, 0.5), (VecX(2) << 0.55, 0.5).finished(),
                                     (VecX(2) << 0.9, 0.9).finished()};
  const double h = 0.1;
  // At the first sample: itself (1) plus the second at distance 0.05: (1 - 0.25)^4.
  EXPECT_NEAR(sample_density(samples[0], samples, h), 1 + std::pow(0.75, 4), 1e-15);
  EXPECT_NEAR(sample_density(samples[2], samples, h), 1.0, 1e-15);
  EXPECT_EQ(sample_density(VecX::Constant(2, 0.2), samples, h), 0.0);
  // Boundary particles beat deep ones; sparse regions beat crowded ones.
  EXPECT_GT(particle_score(0.0, 1.0, 0.1), particle_score(-0.05, 1.0, 0.1));
  EXPECT_EQ(particle_score(-0.2, 1.0, 0.1), 0.0);
  EXPECT_GT(particle_score(0.0, 1.0, 0.1), particle_score(0.0, 2.0, 0.1));
  EXPECT_NEAR(particle_score(-0.05, 2.0, 0.1), 0.5 / 4, 1e-15);
  EXPECT_THROW(sample_density(samples[0], samples, 0.0), InputError);
}

TEST(ParticleScoring, SystematicResamplingCopiesInProportion) {
  std::mt19937_64 rng(9);
  std::vector<double> w(17);
  for (double& x : w) x = double(rng() % 100);
  w[3] = 0;
  const int N = 50;
  double total = 0;
  for (double x : w) total += x;
  for (double u0 : {0.0, 0.3, 0.999}) {
    const std::vector<int> idx = systematic_resample(w, N, u0);
    ASSERT_EQ(static_cast<int>(idx.size()), N);
    EXPECT_TRUE(std::is_sorted(idx.begin(), idx.end()));
    for (int i = 0; i < 17; ++i) {
      const int copies = static_cast<int>(std::count(idx.begin(), idx.end(), i));
      const double expected = N * w[i] / total;
      EXPECT_GE(copies, std::floor(expected) - 1e-9) << i;
      EXPECT_LE(copies, std::ceil(expected) + 1e-9) << i;
    }
    EXPECT_EQ(std::count(idx.begin(), idx.end(), 3), 0);
  }
  EXPECT_THROW(systematic_resample({0.0, 0.0}, 3, 0.5), InputError);
  EXPECT_THROW(systematic_resample({1.0, -1.0}, 3, 0.5), InputError);
  EXPECT_THROW(systematic_resample({1.0}, 3, 1.0), InputError);
}

}  // namespace
}  // namespace msfab
