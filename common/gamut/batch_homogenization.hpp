#pragma once
// Batch homogenization (msfab-homogenize --structures, msfab-family-generate):
// every structure of a `msfab.microstructures` artifact homogenized again,
// optionally refined (each voxel split into refine^3 voxels, or refine^2
// for a 2D cell), with its properties in the set's material space
// recomputed. Uses: a gamut sampled at 16^3 checked at
// 32^3 or 64^3 (the multigrid solver), or a set re-evaluated after a change
// of base materials' void stiffness.
#include <string>

#include "gamut/microstructure_set.hpp"
#include "homog/periodic_homogenization.hpp"

namespace msfab {

struct BatchOptions {
  int refine = 1;
  HomogenizationOptions homogenization;
  int threads = 0;  // 0: the OpenMP default
};

struct BatchReport {
  int structures = 0;
  int outside = 0;                 // properties now outside the space's box (unit coordinates clamped)
  double max_relative_change = 0;  // max over structures of |C_new - C_old| / |C_old|
  double median_relative_change = 0;
  std::string solver;        // solver of the (refined) cells
  long long iterations = 0;  // multigrid CG iterations, all structures
  double seconds = 0;
};

// Structures are independent: with at least as many structures as threads
// they run in parallel (one thread each), otherwise one at a time with the
// threads inside each solve. Both give bitwise the same set.
// InputError for refine < 1 or a refined cell beyond 4096 voxels per axis.
BatchReport homogenize_set(MicrostructureSet& set, const BatchOptions& options);

// The ids of a cell with every voxel split into refine^3 (nz = 1: refine^2).
std::vector<int> refine_ids(const std::vector<int>& ids, int nx, int ny, int nz, int refine);

}  // namespace msfab
