#pragma once
// The V/W-cycle shared by every multigrid in solve/ (assembled, periodic
// grid, component levels; the Dirichlet grid's runs on component levels),
// so that the cycle is written and tuned in one place. Each solver supplies
// its levels' operations, which is where they differ (assembled or
// matrix-free products, lattice or component transfers, a direct or a
// zero-mean coarsest solve).
#include <cstddef>

#include "core/types.hpp"

namespace msfab::multigrid_cycle {

// Smoother degree on the levels below the finest, relative to the finest
// level's: coarse levels are cheap, and a stronger smoother there keeps the
// W-cycle's convergence factor independent of the depth.
constexpr int kCoarseDegreeFactor = 2;
// Coarse corrections per visit of a level below the finest (2: W-cycle).
constexpr int kCoarseCorrections = 2;

// One cycle on level `index` for `rhs`, into `solution`: the coarsest level
// is solved; any other is smoothed from zero, corrected (once on the finest
// level, kCoarseCorrections times below: a V-cycle over W-cycles) by
// restricting the residual, cycling on the next level and adding the
// prolongated correction, and smoothed again. Repeating the same
// symmetric correction keeps the cycle symmetric. `levels` provides
//   bool is_coarsest(i);  void solve_coarsest(i, rhs, x);
//   void smooth(i, rhs, x, bool zero_start);  void residual(i, rhs, x, r);
//   void restrict_to_coarse(i, r, coarse_rhs);  void add_prolongation(i, coarse_x, x);
//   VecX& residual_workspace(i), rhs_workspace(i), solution_workspace(i);
//   int corrections(i).
// The operations alike on every level that keeps its own smoother and cycle
// workspace (members smoother, rhs, solution, residual) in a vector of
// pointers: a Levels type derives from this and adds the rest.
template <class LevelPointers>
struct SmoothedLevels {
  LevelPointers& stored;
  void smooth(std::size_t i, const VecX& b, VecX& x, bool zero_start) { stored[i]->smoother.smooth(b, x, zero_start); }
  void residual(std::size_t i, const VecX& b, const VecX& x, VecX& r) { stored[i]->smoother.residual(b, x, r); }
  VecX& residual_workspace(std::size_t i) { return stored[i]->residual; }
  VecX& rhs_workspace(std::size_t i) { return stored[i]->rhs; }
  VecX& solution_workspace(std::size_t i) { return stored[i]->solution; }
  // Coarse corrections per visit of level i: one on the finest level, a W
  // below. A solver whose level i+1 barely shrinks hides this with its own rule.
  int corrections(std::size_t i) const { return i == 0 ? 1 : kCoarseCorrections; }
};

template <class Levels>
void cycle(Levels& levels, std::size_t index, const VecX& rhs, VecX& solution) {
  if (levels.is_coarsest(index)) {
    levels.solve_coarsest(index, rhs, solution);
    return;
  }
  levels.smooth(index, rhs, solution, /*zero_start=*/true);
  const int corrections = levels.corrections(index);
  for (int c = 0; c < corrections; ++c) {
    VecX& residual = levels.residual_workspace(index);
    VecX& coarse_rhs = levels.rhs_workspace(index + 1);
    VecX& coarse_solution = levels.solution_workspace(index + 1);
    levels.residual(index, rhs, solution, residual);
    levels.restrict_to_coarse(index, residual, coarse_rhs);
    cycle(levels, index + 1, coarse_rhs, coarse_solution);
    levels.add_prolongation(index, coarse_solution, solution);
  }
  levels.smooth(index, rhs, solution, /*zero_start=*/false);
}

}  // namespace msfab::multigrid_cycle
