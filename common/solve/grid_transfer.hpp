#pragma once
// Transfer between two levels of a geometric multigrid hierarchy on a node
// lattice, and the Galerkin coarse operator P^T A P.
//
// P interpolates each displacement component trilinearly: a fine node at
// lattice point f takes weight 1/2^m from each of the 2^m coarse nodes of
// its enclosing coarse cell, m the number of odd coordinates of f (weights
// 1, 1/2, 1/4, 1/8). Rows of P for decoupled fine unknowns (Dirichlet
// unknowns, whose matrix row holds only the diagonal) are zero, so coarse
// corrections leave them alone and their diagonal does not leak into the
// coarse operator.
//
// Two ways to form P^T A P. Where A couples only lattice neighbours (a mesh
// of equal voxels), fixed 3x3x3 boxes of coarse columns per fine row make it
// a table-driven product. Where A couples nodes several lattice steps apart
// (a mesh of mixed element sizes whose hanging nodes are eliminated, as the
// adaptive DDFEM meshes), the level is coarsened by injection
// (coarsen_lattice_by_injection): a fine node takes equal weights from those
// corners of its enclosing coarse cell whose fine point holds a node, or
// weight 1 from the corner at floor(c / 2) where none does, and the product
// runs over each coarse node's children, their fine blocks and the columns'
// parents, with the coarse pattern found the same way.
#include <cstdint>
#include <vector>

#include "solve/block_matrix.hpp"
#include "solve/node_lattice.hpp"

namespace msfab {

class GridTransfer {
 public:
  // Widest coupling accepted, in lattice steps per axis: elements four steps
  // wide whose faces carry eliminated hanging nodes reach five.
  static constexpr int kMaxCouplingSteps = 8;

  // fine_operator holds the block pattern of the fine matrix (node order of
  // `fine`) and reach = lattice_reach(fine, fine_operator), which throws
  // where the matrix is not that of a hex mesh on this lattice. coarse =
  // coarsen_lattice(fine) for reach 1, else coarsen_lattice_by_injection(fine)
  // (the parents then follow that rule). Builds P, the coarse pattern and
  // the index tables of the triple product.
  GridTransfer(const NodeLattice& fine, const NodeLattice& coarse, const BlockMatrix& fine_operator, int reach);

  // The coarse operator's block pattern (values zero).
  BlockMatrix coarse_pattern() const;

  // coarse = P^T fine P, P with the rows of fine_decoupled unknowns zeroed.
  // Coarse unknowns that P does not reach at all get a unit diagonal (their
  // rows and columns are zero otherwise). `coarse` must have the coarse
  // pattern. Exactly symmetric; deterministic for any thread count.
  void galerkin_product(const BlockMatrix& fine, const std::vector<char>& fine_decoupled, BlockMatrix& coarse,
                        int threads);

  // coarse = P^T fine.
  void restrict_to_coarse(const VecX& fine, const std::vector<char>& fine_decoupled, VecX& coarse, int threads) const;
  // fine += P coarse.
  void add_prolongation(const VecX& coarse, const std::vector<char>& fine_decoupled, VecX& fine, int threads) const;

  // P as a sparse matrix (fine unknowns x coarse unknowns), for checks.
  SpMat prolongation(const std::vector<char>& fine_decoupled) const;

  int fine_nodes() const { return static_cast<int>(parent_start_.size()) - 1; }
  int coarse_nodes() const { return static_cast<int>(child_start_.size()) - 1; }
  // True where the fine matrix couples only lattice neighbours (the table-driven product).
  bool neighbour_coupled() const { return neighbour_coupled_; }

 private:
  void build_wide_transfer(const NodeLattice& fine, const NodeLattice& coarse, const BlockMatrix& fine_operator);
  void build_wide_pattern(const BlockMatrix& fine_operator);
  void wide_galerkin_product(const BlockMatrix& fine, const std::vector<char>& fine_decoupled, BlockMatrix& coarse,
                             int threads) const;
  // The lower block triangle of `coarse` from its upper one.
  void mirror_lower_blocks(BlockMatrix& coarse, int team) const;

  bool neighbour_coupled_ = true;
  // Fine node -> its coarse parents (interpolation sources), weight 1/count.
  std::vector<int> parent_start_, parent_node_;
  // Coarse node -> fine children with weights; child_offset_ codes the
  // child's position relative to twice the coarse point.
  std::vector<int> child_start_, child_node_;
  std::vector<double> child_weight_;
  std::vector<std::uint8_t> child_offset_;
  // Per fine node: parity of its coordinates (bit per axis).
  std::vector<std::uint8_t> fine_parity_;
  // Per fine block: lattice offset code of its column node relative to its
  // row node, (dx+1) + 3 (dy+1) + 9 (dz+1).
  std::vector<std::uint8_t> fine_block_offset_;
  // A P, one dense box of coarse columns per fine row: the coarse points
  // that can reach row f, 3 per axis for an even coordinate, else 2.
  std::vector<int> box_start_;
  std::vector<double> fine_times_p_;
  // The coarse pattern; per coarse block its offset code (same coding) and
  // the slot of its transpose.
  BlockMatrix coarse_;
  std::vector<std::uint8_t> coarse_block_offset_;
  std::vector<int> mirror_slot_;
};

// The largest lattice distance (steps on one axis) between two nodes the
// block pattern couples: 1 for a mesh of equal voxels. Throws InputError
// ("pcg-mg needs a voxel mesh: ...") above GridTransfer::kMaxCouplingSteps.
int lattice_reach(const NodeLattice& lattice, const BlockMatrix& matrix);

}  // namespace msfab
