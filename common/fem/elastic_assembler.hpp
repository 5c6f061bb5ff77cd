#pragma once
// Global elastic energy, gradient and sparse Hessian of a hex mesh
// (Algorithm 1, lines 2-17), multithreaded and deterministic.
//
// The Hessian has a fixed pattern built once: every degree of freedom
// couples to the three DOFs of each node sharing an element with it. It is
// stored in full (both triangles) so iterative solvers can multiply with it
// directly; CHOLMOD reads the lower half.
#include <cstdint>
#include <vector>

#include "fem/hex_mesh.hpp"

namespace msfab {

class ElasticAssembler {
 public:
  explicit ElasticAssembler(const HexMesh& mesh);

  const HexMesh& mesh() const { return mesh_; }
  // An all-zero matrix with the Hessian's pattern.
  SpMat pattern() const;

  // x holds deformed positions, node-major (3*n + a). Energies are +inf as
  // soon as one element is inverted.
  double energy(const VecX& x) const;
  // Any of gradient / hessian may be nullptr. `hessian` must carry the
  // pattern returned by pattern(). Returns the energy; if it is +inf the
  // gradient and Hessian are not meaningful.
  double evaluate(const VecX& x, VecX* gradient, SpMat* hessian) const;

  // Positions of the rest configuration, as a DOF vector.
  VecX rest_positions() const;

 private:
  hex8::NodeMatrix gather(const VecX& x, int e) const;

  const HexMesh& mesh_;
  std::vector<int> col_ptr_;   // CSC column starts, size 3N + 1
  std::vector<int> row_idx_;   // CSC row indices
  // For element e, node pair (i, j): the offset of node i's 3-row block in
  // the columns of node j, relative to the column start.
  std::vector<std::array<uint16_t, 64>> block_offset_;
};

}  // namespace msfab
