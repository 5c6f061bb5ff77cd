#pragma once
// The gamut sampler's configuration (docs/gamut.md lists every key).
#include <cstdint>
#include <string>
#include <vector>

#include "gamut/continuous_refinement.hpp"
#include "gamut/gamut_artifact.hpp"
#include "gamut/level_set.hpp"
#include "gamut/material_space.hpp"
#include "gamut/microstructure_set.hpp"
#include "gamut/structure_evolution.hpp"
#include "io/config.hpp"

namespace msfab {

struct SamplerOptions {
  std::string space = "cubic2d";
  MaterialSpaceKind kind = MaterialSpaceKind::cubic2d;
  int resolution = 16;  // voxels per side; a 2D space uses n x n x 1
  BaseMaterial stiff{1e6, 0.3}, soft{1e4, 0.45};
  bool soft_is_void = false;
  // Two materials and void (thesis Fig. 3-15, `materials.void: true` with a
  // soft material): the move adds stiff or soft beams and cuts to void.
  // Discrete sampling only: the continuous and directed steps interpolate
  // between two phases.
  bool three_phase = false;
  double decades = 4;  // log range of the moduli below the stiff E
  double void_stiffness = 1e-6;
  // Cell problems solved on the cell's symmetric part: two strain cases for
  // a cubic cell, one octant for a mirror-symmetric one (both exact);
  // false: six cases on the whole cell (for comparison).
  bool use_symmetry = true;
  // The printer's minimum feature size in voxels: structures with a thinner
  // beam or gap (thin_feature_voxels) are not added. 1: no limit.
  int min_feature = 1;
  // The axis backbone (structure_ops.hpp: add_axis_backbone) of this
  // half-width in voxels added to every structure before it is
  // homogenized, and what it does not reach removed, so that any two
  // structures of the gamut connect at their shared face centres
  // (docs/mapping.md). 0: none. Needs a void phase.
  int backbone = 0;

  // Structures of an earlier set added to the initial population
  // (initial_set.path, a microstructures artifact of the same base
  // materials), each voxel split into initial_set.refine^d: a 16^3 gamut as
  // the start of a 32^3 one, or a cubic set inside an orthotropic space
  // that contains every cubic material. Homogenized again in this space.
  std::string initial_set;
  int initial_refine = 1;

  int population = 24;  // particles
  int cycles = 6;       // discrete + continuous cycles after the initial population (the most)
  // Stop before `cycles` once the gamut has converged: its coverage grew by
  // less than `stop_coverage_growth` (relative) over the last
  // `stop_window` cycles. 0: run all `cycles`.
  double stop_coverage_growth = 0;
  int stop_window = 3;
  int initial_beams = 8;  // beams cut from the solid cell for the initial population
  BeamMoveOptions move;   // the discrete step's move

  int continuous_per_cycle = 4;  // boundary structures refined per cycle (0: discrete only)
  double continuous_step = 0.1;  // |q - p| in the unit cube (the first step when adaptive)
  // Adapt the step to progress: after a cycle in which at least half of
  // the pushes expanded the gamut the step grows 1.5x, after one in which
  // fewer than a quarter did it shrinks 1.5x, within [step / 4, 4 step].
  bool continuous_adaptive = false;
  ContinuousOptions continuous;

  // Directed pushes (docs/gamut.md, "Directed objectives"): per cycle and
  // objective, the `directed_per_cycle` structures furthest along the
  // objective, not yet pushed by it, are optimized along it with the other
  // moduli held above the parent's less `directed_modulus_drop` (unit cube).
  std::vector<std::string> directed_objectives;  // min_nu, max_nu, min_shear, max_shear
  int directed_per_cycle = 0;
  double directed_modulus_drop = 0.25;
  ContinuousOptions directed;  // MMA settings of the directed pushes

  LevelSetOptions level_set{16, 0.1, 0.0, 2};
  double density_radius = 0.1;  // h of Eq. 3.2 (a tenth of the lattice's extent)
  double boundary_depth = 0.1;  // depth of the boundary weight in Eq. 3.1

  // §3.6.1: after sampling, the soft material of every structure replaced
  // by void, cleaned and homogenized again (a second pair of artifacts).
  bool void_variants = false;
  // The baseline of the benchmark: every cycle draws population +
  // continuous_per_cycle * max_iterations fresh random-beam structures from
  // the solid cell (the initial distribution): at least the sampler's
  // number of homogenizations, no evolution, scoring or continuous step.
  bool random_baseline = false;
  // `mode: set`: the gamut of the solid cell and initial_set's structures
  // alone, no random population and no cycles: e.g. a hand-made family
  // whose members connect to each other through their faces
  // (configs/gamut/graded_lattice.yaml, docs/mapping.md).
  bool set_only = false;
};

// The largest coverage of cycles 0..through of `history` (cycle 0 first).
// The coverage itself is not monotone in the samples: the Zhu-Bridson
// function of the level set averages the samples near a point, so a new
// sample inside the gamut can pull the boundary inward (±3% from cycle to
// cycle on the 2D gamuts).
double best_coverage(const std::vector<GamutCycle>& history, std::size_t through);

// The best coverage so far over the best until `window` cycles earlier
// (fewer when the history is shorter), less one; 0 when that is 0.
double best_coverage_growth(const std::vector<GamutCycle>& history, int window);

// True when the best coverage so far exceeds the best coverage until
// `window` cycles earlier by less than `growth` times the latter: the gamut
// stopped growing. False while there are fewer than `window` cycles after
// cycle 0, or when growth is 0.
bool coverage_converged(const std::vector<GamutCycle>& history, double growth, int window);

// The direction in `space`'s unit cube of a named directed objective;
// InputError naming the choices for an unknown name.
VecX directed_direction(const MaterialSpace& space, const std::string& objective);

// InputError naming the key on anything out of range.
SamplerOptions read_sampler_options(const Config& config);

// The built-in defaults: a small 2D cubic gamut of a stiff and a soft material.
extern const char* const kDefaultSamplerConfig;

}  // namespace msfab
