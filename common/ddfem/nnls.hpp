#pragma once
// Non-negative least squares, min ||A x - b|| subject to x >= 0, by the
// active-set method of Lawson and Hanson (Solving Least Squares Problems,
// 1974, ch. 23).
#include "core/types.hpp"

namespace msfab {

struct NnlsResult {
  VecX x;
  double residual = 0;  // ||A x - b||
  int iterations = 0;   // outer iterations (variables freed)
  bool converged = false;
};

// Columns of A should be of comparable scale (the dual tolerance is
// relative to ||A|| ||b||). max_iterations <= 0 means 10 * columns + 10 (3 * columns, the
// textbook cap, was hit by one 192-unknown level-2 fit).
NnlsResult solve_nnls(const MatX& A, const VecX& b, int max_iterations = 0);

}  // namespace msfab
