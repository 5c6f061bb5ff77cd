#pragma once
// Conjugate gradients preconditioned by geometric multigrid for the
// stiffness matrix of a box of nx x ny x nz hexahedra with Dirichlet
// unknowns, applied without assembling it: the FEM solve of 3D topology
// optimization on grids of millions of cells (thesis §3.4, Table 3.2).
// It is the non-periodic sibling of PeriodicGridMultigrid (homogenization)
// and shares its element form, smoothing kernels and CG loop.
//
// The operator is A = D K D + s (I - D): K = sum_e K_e with
// K_e = sum_b w_eb K_b (a VoxelStiffnessField), D the 0/1 diagonal of free
// unknowns, s the mean diagonal of the free unknowns (fixed_scale()). A
// fixed unknown's row is s x_d, so b_d = s u_d prescribes u_d. Memory:
// the weights, a dozen vectors and 9 numbers per row (the inverses of the
// smoother's diagonal blocks); nothing per matrix entry. Rows: every grid
// node, or with material_coarse_space only the nodes that touch a voxel
// with stiffness (a node only void touches must have all three unknowns
// fixed; its solution is b / s without entering CG), so a printed
// structure's vectors hold its material's nodes, not the box's.
//
// Levels: the grid, matrix-free (products element by element in 8 parity
// colours: bitwise deterministic for any thread count); level 1 (every
// other node per axis) assembled as the Galerkin product P^T A P with P
// trilinear and its rows of fixed unknowns zeroed. Trilinear interpolation
// turns the Galerkin product into a sum over the fine elements,
//   K_E = sum_{e in E} P_pos(e)^T D_e K_e D_e P_pos(e),
// so level 1 is built from the weights in one pass (tables P^T K_b P for
// elements without fixed unknowns). Below level 1 the assembled multigrid
// of pcg-mg takes over (MultigridSolver, one cycle per coarse correction).
// The cycle (Chebyshev / block-Jacobi smoothing before and after one
// coarse correction) is a fixed SPD operator, so plain CG applies.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "fem/voxel_stiffness_field.hpp"
#include "solve/block_matrix.hpp"
#include "solve/chebyshev_smoother.hpp"
#include "solve/linear_solver.hpp"

namespace msfab {

class ComponentMultigrid;
class MaterialComponents;
class MultigridSolver;

struct DirichletMultigridOptions {
  double tolerance = 1e-8;  // stop when ||b - A x|| <= tolerance ||b||
  int max_iterations = 2000;
  std::string max_iterations_key;  // the config key that sets max_iterations, for messages (empty: none)
  int smoother_degree = 2;         // Chebyshev degree on the assembled levels (matrix products per smoothing)
  // Chebyshev degree on the grid itself, whose products (element by
  // element) cost most of a cycle. One step is as good a smoother there:
  // on printed structures degree 2 saved no CG iteration (99 against 100
  // on the gripper plate) and cost 40% more time; on SIMP fields it saved
  // at most a third of the iterations for the same time
  // (docs/BENCHMARKS.md, "The matrix-free product on wide vectors").
  // Set here only: solver.mg_smoother_degree sets smoother_degree.
  int grid_smoother_degree = 1;
  int coarse_unknowns = 3000;  // the assembled hierarchy factors its first level with fewer unknowns
  int threads = 0;             // 0: the OpenMP default
  // Coarse spaces that follow the material (solve/material_components.hpp):
  // one copy of a coarse node per connected piece of material in its
  // support, from level 1 down. For voxel models of printed structures
  // (void without stiffness, gaps and thin members); the hierarchy is
  // rebuilt when set_field() changes which voxels have stiffness.
  bool material_coarse_space = false;
  // With material_coarse_space: levels with more blocks than this are held
  // by their upper blocks (kUpperLevelBlocks; tests lower it).
  int upper_level_blocks = kUpperLevelBlocks;
};

// The CG limits, smoother, coarse size and threads of a pcg-mg configuration.
DirichletMultigridOptions dirichlet_multigrid_options(const LinearSolverOptions& options);

class DirichletGridMultigrid {
 public:
  // Node (i, j, k) = i + (nx+1) (j + (ny+1) k), 3 unknowns per node;
  // `fixed`: one flag per unknown. InputError for an invalid option, a
  // grid supports() refuses, or a mask of the wrong size.
  DirichletGridMultigrid(int nx, int ny, int nz, std::vector<char> fixed,
                         const DirichletMultigridOptions& options = {});
  ~DirichletGridMultigrid();
  DirichletGridMultigrid(const DirichletGridMultigrid&) = delete;
  DirichletGridMultigrid& operator=(const DirichletGridMultigrid&) = delete;

  // Every dimension even and at least 2 (level 1 takes every other node).
  static bool supports(int nx, int ny, int nz);

  // New element stiffnesses (field dimensions must match): rebuilds the
  // smoother and the coarse operators. InputError for a mismatched or
  // invalid field, or one where every unknown is fixed; NumericalError if
  // a diagonal block or a coarse operator is not positive definite (part
  // of the body not held by a support).
  void set_field(VoxelStiffnessField field);

  double fixed_scale() const { return fixed_scale_; }
  const std::vector<char>& fixed() const { return fixed_; }
  const VoxelStiffnessField& field() const { return field_; }
  // x with A x = b (one entry per grid unknown). b is released once its
  // rows are gathered, so a caller that moves b in holds no grid vector
  // while CG runs. Throws NumericalError if CG does not converge.
  VecX solve(VecX b);
  // y = A x, matrix-free (one entry per grid unknown).
  void multiply(const VecX& x, VecX& y) const;
  // One cycle z = M^-1 r (one entry per grid unknown; z = r / s at nodes
  // without a row).
  VecX apply_preconditioner(const VecX& r);
  // Nodes that carry unknowns in CG (all nodes without material_coarse_space).
  std::int64_t rows() const { return first_ ? first_->back() : 0; }
  const LinearSolveStats& stats() const { return stats_; }

  // Inspection (small grids): A assembled, level 1 and the masked P.
  SpMat fine_operator() const;
  SpMat coarse_operator() const;
  SpMat prolongation() const;
  // Levels in all: the grid, level 1 and the assembled hierarchy's further levels.
  int num_levels() const;

 private:
  struct Grid {
    int n[3]{0, 0, 0};  // elements per axis; nodes n + 1
    std::int64_t nodes() const { return std::int64_t(n[0] + 1) * (n[1] + 1) * (n[2] + 1); }
    std::int64_t node(int i, int j, int k) const {
      return i + std::int64_t(n[0] + 1) * (j + std::int64_t(n[1] + 1) * k);
    }
    std::int64_t element(int i, int j, int k) const { return i + std::int64_t(n[0]) * (j + std::int64_t(n[1]) * k); }
  };
  void build_fine_smoother();
  // With material_coarse_space: the node copies for the field's solid
  // voxels (rebuilt when they change) and the rows they number.
  void build_material_components();
  void build_coarse_pattern();
  void assemble_coarse();
  void assemble_material_coarse();
  // P_pos and the Galerkin products P_pos^T K_b P_pos of the field's basis.
  void galerkin_tables(std::vector<Mat24>& P, std::vector<Mat24>& galerkin) const;
  // Adds fine voxel (i, j, k)'s share of its coarse element's matrix,
  // P_pos^T D K_e D P_pos (D: its corners' free unknowns).
  void add_voxel_galerkin(int i, int j, int k, int pos, const std::vector<Mat24>& P, const std::vector<Mat24>& galerkin,
                          Mat24& KE) const;
  // Rows from a numbering of the nodes (first[p + 1] > first[p]: node p
  // has row first[p]): the per-row masks and fixed list. NumericalError if
  // a node without a row has a free unknown.
  void number_rows(const std::vector<int>& first);
  int row_of(std::int64_t node) const {
    const int* f = first_->data() + node;
    return f[1] > f[0] ? f[0] : -1;
  }
  // Bit d set if component d of the node is fixed; 7 for a node without a row.
  std::uint8_t node_mask(std::int64_t node) const {
    const int r = row_of(node);
    return r < 0 ? std::uint8_t(7) : row_mask_[std::size_t(r)];
  }
  // Grid vectors (3 per node) to and from row vectors (3 per row); a node
  // without a row takes scale times its entries of `grid`.
  VecX gather_rows(const VecX& grid) const;
  VecX scatter_rows(const VecX& rows_vector, const VecX& grid, double scale) const;
  // The same, written over `grid` itself.
  void scatter_rows_into(const VecX& rows_vector, VecX& grid, double scale) const;
  // y = A x over the rows.
  void multiply_rows(const VecX& x, VecX& y) const;
  void cycle(const VecX& r, VecX& z);
  void restrict_residual(const VecX& fine, VecX& coarse) const;
  void add_prolongation(const VecX& coarse, VecX& fine) const;
  bool is_fixed(std::int64_t unknown) const { return fixed_[std::size_t(unknown)] != 0; }

  Grid fine_, coarse_;
  std::vector<char> fixed_;  // per grid unknown
  std::int64_t fixed_count_ = 0;
  std::vector<int> own_first_;               // the numbering of every node (lattice coarse space)
  const std::vector<int>* first_ = nullptr;  // own_first_ or the material components' level 0
  std::vector<std::uint8_t> row_mask_;       // per row: bit d set if component d is fixed
  std::vector<std::int64_t> fixed_list_;     // the rows' fixed unknowns (3 row + d), ascending
  std::vector<char> coarse_reached_;         // per coarse unknown: some free fine unknown interpolates it
  DirichletMultigridOptions options_;
  VoxelStiffnessField field_;
  bool has_field_ = false;
  double fixed_scale_ = 1.0;
  LinearSolveStats stats_;

  // Grid level: inverses of A's diagonal blocks in single precision (the
  // smoother is only a preconditioner, and a voxel model's blocks are well
  // conditioned: half the bytes of the largest per-row array after the
  // vectors), Chebyshev bound, workspace (product_ also holds the residual
  // that is restricted).
  std::vector<float> inverse_;
  double max_eigenvalue_ = 0.0;
  VecX product_, step_, next_, coarse_rhs_, coarse_solution_;

  // Level 1: block pattern (27 lattice neighbours, -1 outside the grid),
  // its compressed-column copy and the assembled multigrid below it.
  std::vector<int> coarse_slot_;  // 27 per coarse node, by lattice offset code
  BlockMatrix coarse_blocks_;
  SpMat coarse_matrix_;
  std::unique_ptr<MultigridSolver> coarse_solver_;
  bool coarse_analyzed_ = false;

  // With material_coarse_space: the node copies, which voxels they were
  // built for, and the assembled hierarchy from level 1 down.
  std::shared_ptr<const MaterialComponents> components_;
  std::vector<char> components_solid_;
  std::unique_ptr<ComponentMultigrid> component_solver_;
};

}  // namespace msfab
