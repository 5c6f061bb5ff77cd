#pragma once
// Error-driven choice of the coarsening level per level-2 cell ("model only
// what a scene needs"; docs/ddfem.md, "Adaptive coarsening").
//
// The estimate. The scene is solved on the uniform level-2 and level-1
// models. Their difference D (the mean-vertex distance of §2.5.2 between
// the two, both interpolated to the fine nodes) measures how fast the error
// falls with the element size: with errors e_L ~ C h^p, e_1 = D / (2^p - 1)
// and e_2 = 2^p e_1. msfab-simulate takes p = 1, the rate of trilinear elements in
// the energy norm; measured ratios e_2 / e_1 run from 1.5 (level-1 fit errors
// dominate) to 31 (discretization errors dominate), docs/ddfem.md.
//
// A cell whose stiffness is off changes the solution, to first order, by a
// field whose energy norm grows with the square root of the cell's strain
// energy U_c; summing the cells as independent contributions gives for a
// model with level L(c) in cell c
//
//     e = sqrt( sum_c e_{L(c)}^2 U_c / sum_c U_c ),
//
// which equals e_L when every cell has level L, and by Jensen's inequality
// is not below the energy-weighted mean that coherent (same-sign) errors
// would give to first order. U_c comes from the level-1 solve.
//
// The choice. All cells start at level 2; cells are refined greedily by the
// largest decrease of the squared estimate per element added (to level 1 or
// directly to level 0) until the estimate meets the target.
#include <array>
#include <vector>

#include "ddfem/coarse_grid.hpp"

namespace msfab {

struct CellErrorModel {
  double energy_share = 0;        // U_c / sum U
  std::array<int, 3> elements{};  // elements the cell has at levels 0, 1, 2
};

// The uniform models' errors at levels 0, 1, 2 (level 0 is the fine model: 0).
using LevelErrors = std::array<double, 3>;

// e_1 and e_2 from the level-1 / level-2 difference D, for convergence rate p.
LevelErrors level_errors_from_difference(double difference, double rate = 1.0);

struct LevelChoice {
  std::vector<int> cell_level;  // per level-2 cell
  double predicted_error = 0;   // the estimate for these levels
};

// The estimate for given levels.
double predicted_error(const std::vector<CellErrorModel>& cells, const LevelErrors& errors,
                       const std::vector<int>& cell_level);

// Levels meeting `target` (the mean-vertex error) with few elements.
// target 0 gives level 0 everywhere (the fine model). Deterministic.
LevelChoice choose_cell_levels(const std::vector<CellErrorModel>& cells, const LevelErrors& errors, double target);

// The level errors calibrated by a measured solve. A solve at levels
// `levels` had its error measured (`measured_error`, by a fine Newton step)
// together with where it sits (`cell_error_energy`: the fine strain energy
// of the measured error field in each cell). The squared error is split
// between the level-1 and level-2 cells by that energy (fine cells' share is
// induced by the coarse cells around them and left out), and each level's
// error is the one that gives its part with the cells' energy shares:
// e_L^2 = measured^2 (field energy in level-L cells / in coarse cells) /
// (energy share of level-L cells). predicted_error at `levels` is then the
// measured error. A level with no cells keeps its a-priori ratio to the
// other; `errors` is returned where no coarse cell carries field energy.
// Unlike a tightened target, which keeps the a-priori ratio e_2 / e_1, this
// sees where level 1 itself is not good enough and asks for fine cells.
LevelErrors calibrated_level_errors(const std::vector<CellErrorModel>& cells, const LevelErrors& errors,
                                    const std::vector<int>& levels, const std::vector<double>& cell_error_energy,
                                    double measured_error);

// Levels meeting `target` refined from `levels` (no cell coarsened), by the
// greedy rule of choose_cell_levels.
LevelChoice refine_cell_levels(const std::vector<CellErrorModel>& cells, const LevelErrors& errors,
                               const std::vector<int>& levels, double target);

// A mixed solve of an adaptive run as its a-posteriori check saw it.
struct CheckedSolve {
  std::vector<int> cell_level;  // per level-2 cell
  double estimate = 0;          // its a-posteriori error estimate
  bool measured = false;        // a fine Newton estimate; false: the extrapolation
};

// The estimate a solve is ranked by. A measured estimate is its own. The
// extrapolation cannot see error that both uniform levels share, so an
// extrapolated estimate is raised to the measured estimate of any solve
// whose every cell is at the same level or finer: a refinement is not
// less accurate than what it refines (the saturation assumption of the
// refinement bound), so the coarser solve's error is at least about that.
double ranked_estimate(const std::vector<CheckedSolve>& solves, std::size_t index);

// The solve to keep: the smallest ranked estimate; on a tie a measured
// estimate, then the later (finer) solve.
std::size_t kept_solve(const std::vector<CheckedSolve>& solves);

// The cells of `level2` (coarsen_grid(level1)) with their energy shares
// from a solve on the level-1 mesh (`level1_energy` per element of
// level1_mesh) and their element counts per level. All-void cells have no
// elements and no share.
std::vector<CellErrorModel> cell_error_models(const VoxelGrid& fine, const CoarseGrid& level1, const CoarseGrid& level2,
                                              const VoxelMesh& level1_mesh, const std::vector<double>& level1_energy);

// Strain energy of every element of `mesh` at positions x (node-major).
std::vector<double> element_energies(const HexMesh& mesh, const VecX& x);

// The fine strain energy of the displacement field `field` about the state
// `on_fine` (fine-node displacements), summed over each cell of `level2`:
// per element the second difference (E(x + f) + E(x - f)) / 2 - E(x), which
// is f^T K(x) f / 2 to third order (the energy at rest of f where x - f
// inverts an element).
std::vector<double> cell_field_energies(const VoxelMesh& fine, const CoarseGrid& level2, const VecX& on_fine,
                                        const VecX& field);

}  // namespace msfab
