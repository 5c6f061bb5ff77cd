#pragma once
// The assembled part of a multigrid hierarchy whose coarse spaces follow
// the material (solve/material_components.hpp): level 1 of a voxel grid,
// given as a block matrix over its node copies, and the Galerkin products
// P^T A P below it down to a level small enough to factor.
//
// The cycle matches MultigridSolver's: Chebyshev / block-Jacobi smoothing
// before and after each coarse correction, one correction on level 1 and
// two on each level below (a V-cycle over W-cycles), a sparse Cholesky
// factorization on the coarsest level; a fixed symmetric positive definite
// operator, bitwise deterministic for any thread count.
#include <Eigen/SparseCholesky>
#include <memory>
#include <vector>

#include "solve/block_matrix.hpp"
#include "solve/chebyshev_smoother.hpp"
#include "solve/material_components.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {

// The block pattern of level 1's Galerkin operator for the grid's
// hexahedra: copies are coupled when one solid voxel interpolates both
// (values left empty).
BlockMatrix level1_element_pattern(const MaterialComponents& components, int threads);

// coarse = P^T fine P over a transfer (coarse's pattern and values are
// rebuilt); rows and columns of the fine unknowns flagged in
// fine_decoupled are left out (their rows of P are zero). Unknowns that P
// reaches with no stiffness get the mean diagonal of the others.
// `fine_upper`: fine's values are held by its upper blocks
// (upper_block_numbering); the blocks are read in the same order, so an
// exactly symmetric fine gives the same bits either way.
void component_galerkin_product(const BlockMatrix& fine, const std::vector<char>& fine_decoupled,
                                const ComponentTransfer& transfer, BlockMatrix& coarse, int threads,
                                const std::vector<int>* fine_upper = nullptr);

// coarse = P^T fine and fine += P coarse over a transfer, leaving out the
// fine unknowns for which is_free(row, component) is false (their rows of
// P are zero). Rows are independent: the same bits for any thread count.
template <class IsFree>
void component_restrict(const ComponentTransfer& t, const VecX& fine, IsFree&& is_free, VecX& coarse, int threads) {
  const int copies = t.coarse_copies();
  coarse.resize(3 * Eigen::Index(copies));
  parallel_row_ranges(copies, resolve_thread_count(threads), [&](int begin, int end) {
    for (int C = begin; C < end; ++C) {
      double sum[3] = {0, 0, 0};
      for (int s = t.child_start[std::size_t(C)]; s < t.child_start[std::size_t(C) + 1]; ++s) {
        const int f = t.child[std::size_t(s)];
        const double w = t.child_weight[std::size_t(s)];
        for (int d = 0; d < 3; ++d)
          if (is_free(f, d)) sum[d] += w * fine[3 * Eigen::Index(f) + d];
      }
      for (int d = 0; d < 3; ++d) coarse[3 * Eigen::Index(C) + d] = sum[d];
    }
  });
}
template <class IsFree>
void component_add_prolongation(const ComponentTransfer& t, const VecX& coarse, IsFree&& is_free, VecX& fine,
                                int threads) {
  parallel_row_ranges(t.fine_rows(), resolve_thread_count(threads), [&](int begin, int end) {
    for (int f = begin; f < end; ++f) {
      if (t.parent_start[std::size_t(f)] == t.parent_start[std::size_t(f) + 1]) continue;
      double sum[3] = {0, 0, 0};
      for (int s = t.parent_start[std::size_t(f)]; s < t.parent_start[std::size_t(f) + 1]; ++s) {
        const Eigen::Index C = t.parent[std::size_t(s)];
        const double w = t.parent_weight[std::size_t(s)];
        for (int d = 0; d < 3; ++d) sum[d] += w * coarse[3 * C + d];
      }
      for (int d = 0; d < 3; ++d)
        if (is_free(f, d)) fine[3 * Eigen::Index(f) + d] += sum[d];
    }
  });
}

// Gives every unknown of M with a zero diagonal entry the mean diagonal of
// the others (coarse copies that no free fine unknown reaches). `upper`:
// M's values are held by its upper blocks.
void fill_empty_diagonal(BlockMatrix& M, const std::vector<int>* upper = nullptr);

class ComponentMultigrid {
 public:
  // Level 1 is levels()[1] of `components`; its operator is set with
  // level1() and factorize(). smoother_degree: Chebyshev degree on level 1
  // (twice that below). Levels with more than upper_level_blocks blocks
  // are held by their upper blocks (kUpperLevelBlocks; tests lower it to
  // take the large levels' path on small grids).
  ComponentMultigrid(std::shared_ptr<const MaterialComponents> components, int smoother_degree, int threads,
                     int upper_level_blocks = kUpperLevelBlocks);
  ~ComponentMultigrid();
  ComponentMultigrid(const ComponentMultigrid&) = delete;
  ComponentMultigrid& operator=(const ComponentMultigrid&) = delete;

  // Level 1's operator: the pattern of level1_element_pattern(); the caller
  // writes the values, then calls factorize(). Where level1_upper() is not
  // null the values hold only the blocks on and above the diagonal, block
  // (i, j) with j >= i at 9 * (*level1_upper())[slot of (i, j)]; the
  // blocks below are their mirrors' transposes (the operator is symmetric).
  BlockMatrix& level1();
  const std::vector<int>* level1_upper() const;
  // Galerkin operators, smoothers and the coarsest factorization. Returns
  // false if a level is not positive definite.
  bool factorize();
  // One cycle on level 1: z = M^-1 r.
  void cycle(const VecX& r, VecX& z) { cycle(0, r, z); }

  int num_levels() const { return static_cast<int>(levels_.size()); }
  Eigen::Index level_unknowns(int level) const { return level_matrix(level).unknowns(); }
  // Level 1 of a large grid holds no double values after factorize() (its
  // smoother's single-precision copy is what the cycle uses).
  const BlockMatrix& level_matrix(int level) const;

 private:
  struct Level;
  void cycle(std::size_t index, const VecX& rhs, VecX& solution);

  std::shared_ptr<const MaterialComponents> components_;
  int smoother_degree_;
  int threads_;
  int upper_level_blocks_;
  std::vector<std::unique_ptr<Level>> levels_;
  SpMat coarsest_;
  Eigen::SimplicialLLT<SpMat, Eigen::Lower, Eigen::AMDOrdering<int>> coarse_solver_;
  bool coarse_analyzed_ = false;
};

}  // namespace msfab
