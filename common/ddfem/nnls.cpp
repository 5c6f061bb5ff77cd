#include "ddfem/nnls.hpp"

#include <stdexcept>
#include <vector>

namespace msfab {
namespace {

// Least-squares solution on the columns in `passive`, scattered to full size.
VecX solve_on(const MatX& A, const VecX& b, const std::vector<char>& passive) {
  std::vector<int> cols;
  for (int j = 0; j < static_cast<int>(passive.size()); ++j)
    if (passive[j]) cols.push_back(j);
  VecX z = VecX::Zero(A.cols());
  if (cols.empty()) return z;
  MatX Ap(A.rows(), cols.size());
  for (size_t k = 0; k < cols.size(); ++k) Ap.col(k) = A.col(cols[k]);
  const VecX zp = Ap.colPivHouseholderQr().solve(b);
  for (size_t k = 0; k < cols.size(); ++k) z[cols[k]] = zp[k];
  return z;
}

}  // namespace

NnlsResult solve_nnls(const MatX& A, const VecX& b, int max_iterations) {
  if (A.rows() != b.size()) throw std::invalid_argument("solve_nnls: A and b sizes differ");
  const int n = static_cast<int>(A.cols());
  if (max_iterations <= 0) max_iterations = 10 * n + 10;
  NnlsResult r;
  r.x = VecX::Zero(n);
  std::vector<char> passive(n, 0);
  const double tol = 1e-12 * std::max(1.0, A.norm() * b.norm());
  VecX w = A.transpose() * (b - A * r.x);
  // Lawson and Hanson's guard against cycling: a variable whose least-squares
  // value comes out <= 0 the moment it is freed (round-off on a nearly
  // dependent column) is skipped until x changes.
  std::vector<char> blocked(n, 0);
  while (r.iterations < max_iterations) {
    // The most promising variable still held at zero.
    int best = -1;
    for (int j = 0; j < n; ++j)
      if (!passive[j] && !blocked[j] && w[j] > tol && (best < 0 || w[j] > w[best])) best = j;
    if (best < 0) {
      r.converged = true;
      break;
    }
    ++r.iterations;
    passive[best] = 1;
    for (int inner = 0; inner <= n; ++inner) {
      const VecX z = solve_on(A, b, passive);
      if (inner == 0 && z[best] <= 0) {
        passive[best] = 0;
        blocked[best] = 1;
        break;
      }
      std::fill(blocked.begin(), blocked.end(), 0);
      bool feasible = true;
      for (int j = 0; j < n; ++j)
        if (passive[j] && z[j] <= 0) feasible = false;
      if (feasible) {
        r.x = z;
        break;
      }
      // Step from x towards z until the first passive variable hits zero,
      // then return every zero variable to the active set.
      double alpha = 1.0;
      for (int j = 0; j < n; ++j)
        if (passive[j] && z[j] <= 0) alpha = std::min(alpha, r.x[j] / (r.x[j] - z[j]));
      r.x += alpha * (z - r.x);
      for (int j = 0; j < n; ++j)
        if (passive[j] && r.x[j] <= 1e-15 * (1.0 + r.x.cwiseAbs().maxCoeff())) {
          passive[j] = 0;
          r.x[j] = 0;
        }
    }
    // A variable whose column adds nothing (z_j = 0 with x_j = 0) would be
    // picked again forever; w_j is then ~0 and falls below tol.
    w = A.transpose() * (b - A * r.x);
    for (int j = 0; j < n; ++j)
      if (passive[j]) w[j] = 0;
  }
  r.residual = (A * r.x - b).norm();
  return r;
}

}  // namespace msfab
