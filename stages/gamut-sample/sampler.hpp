#pragma once
// The gamut sampler's steps (thesis §3.2), over a state that every MPI rank
// holds identically: the structures found so far, the particle population
// and the per-cycle history.
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "gamut/gamut_artifact.hpp"
#include "gamut/material_space.hpp"
#include "gamut/microstructure_set.hpp"
#include "sampler_options.hpp"

namespace msfab {

struct SamplerState {
  MicrostructureSet set;
  std::vector<std::int64_t> population;  // indices into set.items
  // Per structure: bit 0, already a continuous start; bit 1 + k, already
  // pushed along directed objective k.
  std::vector<std::uint8_t> refined;
  std::vector<GamutCycle> history;
  int cycles_done = -1;  // -1: not initialized; 0: initial population only
  double push_step = 0;  // the level-set push's step now (0: continuous.step)
};

struct StepReport {
  int tried = 0, added = 0;
  // rejected: already in the set, outside the space's box, a feature below min_feature, no result
  int duplicates = 0, outside = 0, thin = 0, failed = 0;
  int expanded = 0;  // level-set pushes: added structures outside the gamut they were pushed from
  double step = 0;   // level-set pushes: the step they used
};

class GamutSampler {
 public:
  GamutSampler(const SamplerOptions& options, std::uint64_t seed);

  // Cycle 0: the solid cell and `population` structures cut from it by
  // random beams, homogenized; the population resampled from them.
  SamplerState initialize(StepReport* report) const;
  // §3.2.1: every particle evolved by random beams; new structures added.
  StepReport discrete_step(SamplerState& state, int cycle) const;
  // §3.2.2: up to continuous_per_cycle unrefined structures nearest the
  // boundary pushed along the level set's normal by MMA.
  StepReport continuous_step(SamplerState& state, const GamutLevelSet& gamut, int cycle) const;
  // Directed pushes: per objective, the directed_per_cycle structures
  // furthest along it that it has not pushed yet, optimized along it by
  // MMA with the other moduli floored at the parent's less modulus_drop.
  StepReport directed_step(SamplerState& state, int cycle) const;
  // §3.6.1: every structure with its soft material replaced by void,
  // cleaned (floating pieces dropped, 3D cavities filled) and homogenized
  // again; structures left empty, outside the space or repeated are dropped.
  SamplerState void_variants(const SamplerState& state, StepReport* report) const;
  // §3.2.3 on the current structures.
  GamutLevelSet level_set(const SamplerState& state) const;
  // Eq. 3.1-3.2 scores of every structure, then systematic resampling.
  void resample(SamplerState& state, const GamutLevelSet& gamut, int cycle) const;

  const MaterialSpace& space() const { return space_; }

 private:
  SamplerOptions o_;
  std::uint64_t seed_;
  MaterialSpace space_;
  std::vector<MaterialPtr> palette_;       // [0] void, [1] stiff, [2] soft (if any)
  std::vector<MaterialPtr> void_palette_;  // [0] void, [1] stiff
  int voxels_per_side_z() const;
  // A cell of the sampler's resolution with these ids, or with a structure's.
  VoxelGrid cell_with(std::vector<int> ids) const;
  VoxelGrid cell_of(const Microstructure& m) const;
  VoxelGrid solid_cell() const;
  // `count` structures cut from the solid cell by up to initial_beams beams
  // (the initial distribution, and the random baseline's draws).
  std::vector<VoxelGrid> random_cuts(int cycle, int count) const;
  // The cells of options.initial_set, refined; InputError naming the file
  // if they do not fit this sampler (dimension, resolution, materials).
  std::vector<VoxelGrid> initial_set_cells() const;
  // Homogenizes `cells` (ids into `palette`) across ranks; appends the new, valid, unique ones.
  StepReport add_structures(SamplerState& state, const std::vector<VoxelGrid>& cells,
                            const std::vector<std::int64_t>& parents, int cycle, SampleStep step,
                            const std::vector<MaterialPtr>& palette) const;
  bool fill_properties(Microstructure& m, const Mat6& C, double rho) const;
  // Runs refine(i) for every start across ranks (nullopt: no result) and
  // adds the new structures with the start as parent.
  StepReport add_refined(SamplerState& state, const std::vector<std::int64_t>& starts, int cycle, SampleStep step,
                         const std::function<std::optional<VoxelGrid>(int)>& refine) const;
};

}  // namespace msfab
