#pragma once
// Conjugate gradients preconditioned by geometric multigrid for the periodic
// stiffness matrix of a voxel grid: the cell problem of homogenization at 32^3,
// 64^3 and beyond, where a sparse factorization runs out of time and memory.
//
// Finest level: matrix-free. K x is a sum of element products K_v x_v,
// K_v = sum_b w_vb K_b (VoxelStiffnessField), computed colour by colour
// (voxels of one coordinate parity share no node) so that additions never
// conflict and always come in the same order. Memory is the weights plus a
// few vectors (and 18 numbers per node for the smoother's diagonal blocks
// and their inverses).
// Coarse levels: every other lattice point per axis, trilinear prolongation
// P, Galerkin operators P^T K P. Trilinear interpolation of nested grids
// composes, so the Galerkin operator of level l is itself an element sum,
//   K_E = sum_{voxels v in E} sum_b w_vb Q_l[pos(v)][b],
//   Q_l[pos][b] = P_pos^T K_b P_pos,
// with P_pos the interpolation from coarse element E's corners to the
// corners of the voxel at relative position pos. Each level is built from
// the finest weights in one pass, never from the level above, and is
// stored assembled (27 node blocks per row) for the Chebyshev smoother.
// Coarsest level: a sparse Cholesky factorization with one node pinned.
//
// The matrix is singular: periodic fields are defined up to a translation.
// Right-hand sides are projected to zero mean per component, and so is the
// output of every cycle; CG then runs in the zero-mean subspace, where K is
// positive definite (for a connected cell). V-cycle on the finest level,
// W-cycles below; Chebyshev / block-Jacobi smoothing (solve/chebyshev_kernels.hpp).
// Every kernel gathers per output row, so results are bitwise identical for
// any thread count.
#include <Eigen/SparseCholesky>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "fem/voxel_stiffness_field.hpp"
#include "solve/linear_solver.hpp"

namespace msfab {

struct PeriodicMultigridOptions {
  double tolerance = 1e-8;  // stop when ||b - K x|| <= tolerance ||b|| (b projected)
  int max_iterations = 1000;
  std::string max_iterations_key;  // the config key that sets max_iterations, for messages (empty: none)
  int smoother_degree = 2;         // Chebyshev degree on the finest level (twice that below)
  int coarsest_nodes = 64;         // coarsening stops at the first level with at most this many nodes
  // Coarse levels' smoothers in single precision (ChebyshevSmoother). A
  // stiffness contrast beyond what single precision resolves (e.g. void at
  // 1e-9 of the solid) can make the rounded operators indefinite; solve()
  // detects that (r . M^-1 r <= 0) and switches to double precision once.
  bool single_precision_smoothers = true;
  int threads = 0;  // 0: the OpenMP default
};

class PeriodicGridMultigrid {
 public:
  // Builds the hierarchy and the smoothers. InputError for an invalid field
  // or option, or a grid that cannot be coarsened once (see supports());
  // NumericalError if a diagonal block or the coarsest matrix is not
  // positive definite (a cell whose solid falls apart).
  PeriodicGridMultigrid(VoxelStiffnessField field, const PeriodicMultigridOptions& options = {});
  ~PeriodicGridMultigrid();
  PeriodicGridMultigrid(const PeriodicGridMultigrid&) = delete;
  PeriodicGridMultigrid& operator=(const PeriodicGridMultigrid&) = delete;

  // A grid has a coarser level when every dimension is even and at least 4.
  static bool supports(int nx, int ny, int nz);

  // x with K x = b - mean(b), of zero mean per component. b: 3 entries per
  // node, node (i, j, k) = i + nx (j + ny k). Throws NumericalError if CG
  // does not converge within max_iterations, or if the preconditioner is
  // indefinite with double-precision smoothers too.
  VecX solve(const VecX& b);
  // Whether the coarse levels' smoothers use single precision (false after
  // the fallback of solve()).
  bool single_precision_smoothers() const { return single_precision_smoothers_; }
  const LinearSolveStats& stats() const { return stats_; }

  // y = K x (finest level, matrix-free, element by element in 8 colours).
  void multiply(const VecX& x, VecX& y) const;
  // One cycle z = M^-1 r (r and z of zero mean).
  VecX apply_preconditioner(const VecX& r);

  // Inspection. Level 0 is the voxel grid; num_levels() - 1 the coarsest.
  int num_levels() const { return static_cast<int>(levels_.size()); }
  std::array<int, 3> level_dims(int level) const;
  // The operator of a level, assembled (level 0 too, for checks).
  SpMat level_operator(int level) const;
  // Prolongation from level + 1 to level.
  SpMat prolongation(int level) const;

 private:
  struct Level;
  void build_level(std::size_t l);
  VecX solve_cg(const VecX& consistent);
  void cycle(std::size_t level, const VecX& rhs, VecX& solution);
  // The row-wise view the Chebyshev kernels take: node row i of the product
  // last computed into fine_product_ (their before_pass hook computes it).
  auto fine_rows() const {
    return [this](int i, const double*, double out[3]) {
      const double* y = fine_product_.data() + 3 * std::size_t(i);
      out[0] = y[0], out[1] = y[1], out[2] = y[2];
    };
  }
  // K_E of element `element` of level l (l >= 1) from the level's Galerkin
  // tables galerkin[pos * basis + b] = P_pos^T K_b P_pos.
  Mat24 coarse_element(std::size_t l, std::int64_t element, const std::vector<Mat24>& galerkin) const;

  VoxelStiffnessField field_;
  PeriodicMultigridOptions options_;
  bool single_precision_smoothers_ = true;
  LinearSolveStats stats_;
  std::vector<std::unique_ptr<Level>> levels_;
  // Finest level: diagonal blocks and their inverses, smoother bound,
  // workspace (fine_product_ holds K x for the row-wise smoothing kernels).
  std::vector<double> fine_diagonal_, fine_inverse_;
  double fine_max_eigenvalue_ = 0.0;
  VecX step_, next_, fine_product_;
  // Coarsest level: full operator (for checks) and its factorization with node 0 pinned.
  SpMat coarsest_full_;
  Eigen::SimplicialLLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>> coarse_solver_;
};

}  // namespace msfab
