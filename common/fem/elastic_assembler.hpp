#pragma once
// Global elastic energy, gradient and sparse Hessian of a hex mesh
// (Algorithm 1, lines 2-17), multithreaded and deterministic.
//
// The Hessian has a fixed pattern built once: every degree of freedom
// couples to the three DOFs of each node sharing an element with it. It is
// stored in full (both triangles) so iterative solvers can multiply with it
// directly; CHOLMOD reads the lower half.
#include <cstdint>
#include <memory>
#include <vector>

#include "fem/hex_mesh.hpp"

namespace msfab {

// Linear constraints between mesh nodes: the positions of all mesh nodes are
// x = T y for the positions y of the unknown nodes (T applied per
// coordinate). Hanging nodes of a mesh whose elements differ in size
// (ddfem/mixed_level_mesh.hpp) are interpolated this way from the corners of
// the larger element whose face or edge they lie on, which keeps the
// displacement field continuous.
struct NodeConstraints {
  SpMat node_map;          // (mesh nodes) x (unknown nodes); rows sum to 1
  NodeArray unknown_rest;  // rest positions of the unknown nodes
};

class ElasticAssembler {
 public:
  explicit ElasticAssembler(const HexMesh& mesh);
  // With constraints, every vector and matrix below is over the unknown
  // nodes: the energy is E(T y), the gradient T^T g and the Hessian T^T K T.
  ElasticAssembler(const HexMesh& mesh, std::shared_ptr<const NodeConstraints> constraints);

  const HexMesh& mesh() const { return mesh_; }
  // Unknowns: 3 per mesh node, or 3 per unknown node with constraints.
  int num_dofs() const;
  // Rest positions of the nodes that carry the unknowns, one row each.
  const NodeArray& unknown_rest_nodes() const;
  // An all-zero matrix with the Hessian's pattern.
  SpMat pattern() const;

  // x holds deformed positions, node-major (3*n + a). Energies are +inf as
  // soon as one element is inverted.
  //
  // Elements with bubble modes keep their last bubble amplitudes as the
  // warm start of the next evaluation (hex_evaluate), so one assembler must
  // not be evaluated from two threads at once; its results do not depend on
  // the thread count (each element's amplitudes follow its own evaluations).
  double energy(const VecX& x) const;
  // Any of gradient / hessian may be nullptr. `hessian` must carry the
  // pattern returned by pattern(). Returns the energy; if it is +inf the
  // gradient and Hessian are not meaningful.
  double evaluate(const VecX& x, VecX* gradient, SpMat* hessian) const;

  // Positions of the rest configuration, as a DOF vector.
  VecX rest_positions() const;
  // Positions of every mesh node for the unknowns x (x itself without
  // constraints).
  VecX mesh_positions(const VecX& x) const;

 private:
  hex8::NodeMatrix gather(const VecX& x, int e) const;
  SpMat mesh_pattern() const;
  double evaluate_mesh(const VecX& x, VecX* gradient, SpMat* hessian) const;

  const HexMesh& mesh_;
  std::vector<int> col_ptr_;  // CSC column starts, size 3N + 1
  std::vector<int> row_idx_;  // CSC row indices
  // For element e, node pair (i, j): the offset of node i's 3-row block in
  // the columns of node j, relative to the column start.
  std::vector<std::array<uint16_t, 64>> block_offset_;
  // Constraints: T per DOF (3 rows per mesh node), its transpose, the
  // reduced pattern T^T K T, and how each value of the mesh Hessian adds
  // into it: reduced[to[k]] += weight[k] * mesh[from[k]], in an order fixed
  // at construction.
  std::shared_ptr<const NodeConstraints> constraints_;
  SpMat dof_map_, dof_map_t_, reduced_pattern_;
  std::vector<int> reduce_from_, reduce_to_;
  std::vector<double> reduce_weight_;
  // The bubble states (hex_element.hpp) of the elements with bubble modes,
  // and each element's slot among them (-1 without; both empty when no
  // element has bubble modes). A cache: it changes no result beyond the
  // condensation's tolerance, only the cost.
  std::vector<int> bubble_slot_;
  mutable std::vector<BubbleState> bubbles_;
};

}  // namespace msfab
