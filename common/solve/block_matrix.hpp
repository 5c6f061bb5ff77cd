#pragma once
// Symmetric matrices of 3x3 node blocks (3 unknowns per node, node-major),
// stored by block rows. Elasticity stiffness matrices couple every unknown
// of a node to every unknown of its neighbours, so one column index per
// block instead of per entry cuts the memory traffic of a product by a third.
#include <omp.h>

#include <vector>

#include "core/types.hpp"

namespace msfab {

struct BlockMatrix {
  int rows = 0;                // block rows (nodes)
  std::vector<int> row_start;  // size rows + 1
  std::vector<int> column;     // block column of each stored block, ascending within a row
  std::vector<int> diagonal;   // slot of block (i, i) in row i
  std::vector<double> values;  // 9 per block, row-major: entry (a, b) at 9 * slot + 3 * a + b

  int num_blocks() const { return row_start.empty() ? 0 : row_start.back(); }
  Eigen::Index unknowns() const { return 3 * Eigen::Index(rows); }
};

// Calls body(begin, end) on contiguous row ranges that split [0, n) among
// the OpenMP team. For kernels whose rows are independent (each output
// written once), the result does not depend on the split.
template <class RangeBody>
void parallel_row_ranges(int n, int team, RangeBody&& body) {
  if (team <= 1 || n < 2048) {
    body(0, n);
    return;
  }
#pragma omp parallel num_threads(team)
  {
    const int count = omp_get_num_threads();
    const int me = omp_get_thread_num();
    const long long begin = (long long)n * me / count;
    const long long end = (long long)n * (me + 1) / count;
    body(static_cast<int>(begin), static_cast<int>(end));
  }
}

// y += m x for a 3x3 block m stored row by row, or y += m^T x.
template <class Value>
inline void add_block_product(const Value* m, const double* x, double& y0, double& y1, double& y2) {
  y0 += double(m[0]) * x[0] + double(m[1]) * x[1] + double(m[2]) * x[2];
  y1 += double(m[3]) * x[0] + double(m[4]) * x[1] + double(m[5]) * x[2];
  y2 += double(m[6]) * x[0] + double(m[7]) * x[1] + double(m[8]) * x[2];
}
template <class Value>
inline void add_transposed_block_product(const Value* m, const double* x, double& y0, double& y1, double& y2) {
  y0 += double(m[0]) * x[0] + double(m[3]) * x[1] + double(m[6]) * x[2];
  y1 += double(m[1]) * x[0] + double(m[4]) * x[1] + double(m[7]) * x[2];
  y2 += double(m[2]) * x[0] + double(m[5]) * x[1] + double(m[8]) * x[2];
}

// Block row i of M times x: out[a] = sum_j M_ij(a, :) x_j, with the values
// taken from `values` (laid out like M.values; float for a compact copy).
template <class Value>
inline void block_row_product(const BlockMatrix& M, const Value* values, int i, const double* x, double out[3]) {
  double y0 = 0.0, y1 = 0.0, y2 = 0.0;
  const int* column = M.column.data();
  for (int slot = M.row_start[i]; slot < M.row_start[i + 1]; ++slot) {
    add_block_product(values + 9 * std::size_t(slot), x + 3 * std::size_t(column[slot]), y0, y1, y2);
  }
  out[0] = y0;
  out[1] = y1;
  out[2] = y2;
}
inline void block_row_product(const BlockMatrix& M, int i, const double* x, double out[3]) {
  block_row_product(M, M.values.data(), i, x, out);
}

// Block pattern of A (n x n, n a multiple of 3, symmetric pattern): block
// (I, J) is stored if any entry of it is, and every diagonal block is.
// Throws std::invalid_argument if n is not a multiple of 3.
BlockMatrix block_pattern(const SpMat& A);

// Copies the values of A + shift I into M (built by block_pattern(A));
// entries A does not store are zero. A is symmetric, so block row I is read
// from columns 3I..3I+2 of the compressed column storage.
void copy_block_values(const SpMat& A, double shift, BlockMatrix& M, int threads);

// y = M x.
void block_multiply(const BlockMatrix& M, const VecX& x, VecX& y, int threads);

// A symmetric block matrix held by its blocks on and above the diagonal
// only: half the bytes of the values, for operators too large to hold
// twice (level 1 of a voxel model's multigrid). The upper blocks are
// numbered row by row; `upper` gives, per slot of the pattern, the block it
// reads, the mirror's for a slot below the diagonal (read transposed). The
// values then hold 9 per upper block, row-major. std::logic_error if the
// pattern is not symmetric.
std::vector<int> upper_block_numbering(const BlockMatrix& M, int threads);
// The number of upper blocks of M's pattern (diagonal included).
std::size_t upper_block_count(const BlockMatrix& M);

// Where block `slot`'s values are stored in M.values: at the slot itself,
// or with `upper` (upper_block_numbering) at its upper block (below the
// diagonal: the mirror, not transposed).
inline std::size_t stored_block(const std::vector<int>* upper, int slot) {
  return 9 * (upper ? std::size_t((*upper)[std::size_t(slot)]) : std::size_t(slot));
}

// Block `slot` (in row i) of M into out, row-major: read from M.values as
// stored, or with `upper` (upper_block_numbering) from its upper block,
// transposed below the diagonal.
inline void read_block(const BlockMatrix& M, const std::vector<int>* upper, int i, int slot, double out[9]) {
  const double* m = M.values.data() + stored_block(upper, slot);
  if (!upper || M.column[std::size_t(slot)] >= i) {
    for (int e = 0; e < 9; ++e) out[e] = m[e];
  } else {
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 3; ++q) out[3 * r + q] = m[3 * q + r];
  }
}

// Per unknown: 1 if its row holds no non-zero but the diagonal (a Dirichlet
// unknown whose row and column were cleared), else 0. `upper`: M's values
// are held by its upper blocks (upper_block_numbering).
std::vector<char> decoupled_unknowns(const BlockMatrix& M, int threads, const std::vector<int>* upper = nullptr);

// M as compressed column storage with both triangles, every block stored in
// full (the pattern; values are filled by copy_to_sparse()).
SpMat sparse_pattern(const BlockMatrix& M);
void copy_to_sparse(const BlockMatrix& M, SpMat& S);

}  // namespace msfab
