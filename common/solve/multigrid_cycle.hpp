#pragma once
// The shape of the V/W-cycle shared by every multigrid in solve/ (assembled,
// periodic grid, component levels), so that the cycle is tuned in one place.

namespace msfab::multigrid_cycle {

// Smoother degree on the levels below the finest, relative to the finest
// level's: coarse levels are cheap, and a stronger smoother there keeps the
// W-cycle's convergence factor independent of the depth.
constexpr int kCoarseDegreeFactor = 2;
// Coarse corrections per visit of a level below the finest (2: W-cycle).
constexpr int kCoarseCorrections = 2;

}  // namespace msfab::multigrid_cycle
