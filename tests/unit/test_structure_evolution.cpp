// The discrete step's beam move, and a small discrete sampling run that
// widens the 2D gamut (the sampler's inner loop, without MPI or artifacts).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "gamut/level_set.hpp"
#include "gamut/material_space.hpp"
#include "gamut/particle_scoring.hpp"
#include "gamut/structure_evolution.hpp"
#include "gamut/structure_ops.hpp"
#include "homog/periodic_homogenization.hpp"
#include "material/linear_isotropic.hpp"

namespace msfab {
namespace {

TEST(StructureEvolution, MovesGiveSymmetricCleanStructuresDeterministically) {
  VoxelGrid start(12, 12, 12, 1.0 / 12, 1);
  const VoxelGrid a = evolve_structure(start, 5), b = evolve_structure(start, 5), c = evolve_structure(start, 6);
  EXPECT_EQ(a.ids, b.ids);
  EXPECT_NE(a.ids, c.ids);
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    VoxelGrid s = evolve_structure(start, seed);
    EXPECT_TRUE(has_cubic_symmetry(s));
    VoxelGrid again = s;
    const CleanupReport r = clean_structure(again);  // already clean
    EXPECT_EQ(r.removed_voxels + r.filled_voxels, 0) << seed;
  }
}

TEST(StructureEvolution, DiscreteSamplingWidensTheGamutOverRandomMoves) {
  // 2D cubic space, two materials 1000 apart (nu 0.45), 12 x 12 cells.
  const std::vector<MaterialPtr> pal = {nullptr, std::make_shared<LinearIsotropic>(1e6, 0.45),
                                        std::make_shared<LinearIsotropic>(1e3, 0.45)};
  const MaterialSpace space(MaterialSpaceKind::cubic2d, 1e6);
  BeamMoveOptions move;
  move.materials = 2;
  auto evaluate = [&](const VoxelGrid& cell) {
    const PlaneStrainResult r = homogenize_plane_strain(cell, pal);
    return space.normalize(space.properties_2d(r.C, r.full.volume_fraction[1]));
  };
  std::vector<VoxelGrid> population(8, VoxelGrid(12, 12, 1, 1.0 / 12, 1));
  std::vector<VecX> samples = {evaluate(population[0])};
  std::uint64_t seed = 100;
  const int cycles = 6;
  for (int cycle = 0; cycle < cycles; ++cycle) {
    // Evolve every particle, evaluate, and keep all results as samples.
    std::vector<VecX> props;
    for (VoxelGrid& p : population) {
      VoxelGrid next = evolve_structure(p, seed++, move);
      if (next.count_solid() == 0) next = p;
      p = next;
      props.push_back(evaluate(p));
      samples.push_back(props.back());
    }
    // Score against the current gamut and resample.
    std::vector<VecX> clipped;
    for (const VecX& s : samples) clipped.push_back(s.cwiseMax(0.0).cwiseMin(1.0));
    LevelSetOptions lo;
    lo.cells = 10;
    const GamutLevelSet gamut = GamutLevelSet::from_points(clipped, lo);
    std::vector<double> w;
    for (const VecX& p : props) {
      const VecX q = p.cwiseMax(0.0).cwiseMin(1.0);
      w.push_back(1e-6 + particle_score(gamut.value(q), sample_density(q, clipped, 0.1), 0.2));
    }
    const std::vector<int> keep = systematic_resample(w, static_cast<int>(population.size()), 0.5);
    std::vector<VoxelGrid> next;
    for (int i : keep) next.push_back(population[i]);
    population = next;
  }
  // The samples now span a range of stiffness and Poisson's ratio that the
  // solid start (one point) did not.
  double e_min = 1, e_max = 0, nu_min = 1, nu_max = 0;
  for (const VecX& s : samples) {
    e_min = std::min(e_min, s[0]), e_max = std::max(e_max, s[0]);
    nu_min = std::min(nu_min, s[1]), nu_max = std::max(nu_max, s[1]);
  }
  std::printf("[sampler] %zu samples: normalized E in [%.3f, %.3f], nu in [%.3f, %.3f]\n", samples.size(), e_min, e_max,
              nu_min, nu_max);
  EXPECT_GT(e_max - e_min, 0.1);
  EXPECT_GT(nu_max - nu_min, 0.02);
}

}  // namespace
}  // namespace msfab
