#include "ddfem/block_newton.hpp"

#include <cmath>

namespace msfab {

bool shifted_descent_step(const MatX& H, const VecX& g, VecX& step) {
  const int m = static_cast<int>(H.rows());
  const double diag = H.diagonal().cwiseAbs().maxCoeff();
  double shift = 0;
  for (int attempt = 0; attempt < 12; ++attempt) {
    Eigen::LDLT<MatX> ldlt(H + shift * MatX::Identity(m, m));
    if (ldlt.info() == Eigen::Success && ldlt.isPositive()) {
      step = -ldlt.solve(g);
      if (step.allFinite() && step.dot(g) < 0) return true;
    }
    shift = shift == 0 ? 1e-8 * diag : shift * 10;
  }
  return false;
}

bool energy_step_accepted(double trial, double current, double alpha, double slope, bool first_trial) {
  return std::isfinite(trial) &&
         (trial <= current + 1e-4 * alpha * slope ||
          (first_trial && std::abs(trial - current) <= 1e-13 * std::max(1.0, std::abs(current))));
}

double largest_small_strain(const Mat3& grad_u) {
  const Mat3 eps = 0.5 * (grad_u + grad_u.transpose());
  return Eigen::SelfAdjointEigenSolver<Mat3>(eps).eigenvalues().cwiseAbs().maxCoeff();
}

}  // namespace msfab
