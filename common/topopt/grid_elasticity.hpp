#pragma once
// Linear elasticity on a CellGrid with a stiffness per cell: assembly of
// K = sum_e K_e(C_e), Dirichlet conditions, solves for loads and adjoints,
// and the per-cell products a_e^T B_st b_e that every adjoint gradient of
// the topology optimizer is built from (thesis §3.4, Eq. 3.6).
//
// Fixed unknowns stay in the system as rows and columns of a scaled
// identity (their values move to the right-hand side), so the matrix keeps
// `dimension` unknowns per lattice node and pcg-mg applies on 3D grids.
// Assembly runs over cells in 2^d parity colours (cells of one colour
// share no node), so it is parallel and bitwise deterministic.
//
// Solver "matrix-free" (3D grids with even dimensions) never assembles K:
// DirichletGridMultigrid applies it cell by cell from the per-cell
// stiffness, so memory stays at a few vectors per unknown (the grids of
// Table 3.2, up to millions of cells).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "fem/voxel_stiffness_field.hpp"
#include "solve/linear_solver.hpp"
#include "topopt/cell_grid.hpp"

namespace msfab {

struct GridSolveStats {
  int solves = 0;  // load and adjoint solves so far
  int factorizations = 0;
  long long iterations = 0;  // CG iterations over all solves (iterative solvers)
  double assemble_seconds = 0, factorize_seconds = 0, solve_seconds = 0;
};

class DirichletGridMultigrid;

// The element stiffnesses of a 3D grid as a VoxelStiffnessField with as few
// base matrices as the pairs allow: pair columns that are proportional over
// all cells (to 1e-13 relative) share one base matrix, all-zero columns
// drop out. SIMP (C = scale x C0) needs one, a cubic material three
// (C11, C12, C44); a product then costs that many 24 x 24 products per cell.
VoxelStiffnessField stiffness_field(const CellGrid& grid, const MatX& pairs);

class GridElasticity {
 public:
  // `fixed`: one flag per unknown. solver: "cholmod" | "pcg-mg" (3D only) |
  // "matrix-free" (3D, even dimensions) | "auto" (cholmod in 2D; in 3D
  // matrix-free above 30k unknowns where the dimensions are even, pcg-mg
  // above 300k where they are not, else cholmod). material_coarse_space:
  // the matrix-free solver's coarse spaces follow the material
  // (DirichletMultigridOptions), for voxel models of printed structures.
  GridElasticity(const CellGrid& grid, std::vector<char> fixed, const std::string& solver,
                 const LinearSolverOptions& options, bool material_coarse_space = false);
  ~GridElasticity();

  const CellGrid& grid() const { return grid_; }
  const std::vector<char>& fixed() const;
  const std::string& solver_name() const { return solver_name_; }

  // C_st (s <= t, CellGrid::pair_index order) per cell: cells x voigt_pairs.
  // Assembles and factorizes; NumericalError if K is not positive definite.
  void set_stiffness(const MatX& pairs);
  // Solver "matrix-free" only: the element stiffnesses as a field (its
  // dimensions the grid's, its voxel size h), without the cells x 21 table:
  // a voxel model of a few materials then costs a weight or two per cell.
  void set_field(VoxelStiffnessField field);
  // Displacement for nodal forces with the fixed unknowns at `prescribed`
  // (entries at free unknowns are ignored; an empty vector means zeros).
  // The right-hand side is built in `force`: move it in where it is not
  // needed afterwards (a grid vector less on large voxel models).
  VecX solve(VecX force, const VecX& prescribed = VecX());
  // K_ff^-1 restricted to the free unknowns; rhs must vanish on fixed ones.
  VecX solve_adjoint(const VecX& rhs);
  // Per cell and pair: a_e^T B_st b_e (cells x voigt_pairs).
  MatX pair_products(const VecX& a, const VecX& b) const;
  // The strain energy 1/2 u^T K u.
  double energy(const VecX& u) const;
  const GridSolveStats& stats() const { return stats_; }

 private:
  void build_pattern();
  VecX run_solve(VecX rhs);
  // K_e of a cell, from the field (matrix-free) or the pairs.
  MatX element_matrix(std::int64_t cell) const;

  CellGrid grid_;
  std::vector<char> fixed_;
  std::string solver_name_;
  LinearSolverOptions options_;
  std::unique_ptr<LinearSolver> solver_;                 // assembled solvers
  std::unique_ptr<DirichletGridMultigrid> matrix_free_;  // or this
  SpMat K_;
  std::vector<int> slot_;        // cells x ne x ne: value index of each element entry, -1 if dropped
  std::vector<int> fixed_slot_;  // diagonal value index of each fixed unknown
  std::vector<std::vector<std::int64_t>> colours_;
  MatX pairs_;
  double fixed_scale_ = 1.0;
  bool analyzed_ = false;
  GridSolveStats stats_;
};

}  // namespace msfab
