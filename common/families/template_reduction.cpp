#include "families/template_reduction.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <string>

#include "core/errors.hpp"

namespace msfab {

ReducedTemplate reduce_template_parameters(const MatX& parameters, const MatX& properties,
                                           const ReductionOptions& options) {
  const Eigen::Index m = parameters.rows();
  if (m < 3) throw InputError("reduced template parameters need at least 3 fitted members, got " + std::to_string(m));
  if (properties.rows() != m || properties.cols() != 2)
    throw InputError("reduced template parameters: properties must be members x 2 (log10 E, nu)");
  if (options.reduced < 1) throw InputError("reduced template parameters: reduced must be >= 1");
  if (!(options.variance_kept > 0 && options.variance_kept <= 1))
    throw InputError("reduced template parameters: variance_kept must be in (0, 1]");

  ReducedTemplate out;
  out.base = parameters.colwise().mean().transpose();
  const MatX P = parameters.rowwise() - out.base.transpose();
  const Eigen::RowVectorXd y_mean = properties.colwise().mean();
  const MatX Y = properties.rowwise() - y_mean;

  Eigen::JacobiSVD<MatX> svd(P, Eigen::ComputeThinV);
  const VecX sigma = svd.singularValues();
  const double total = sigma.squaredNorm();
  int q = 0;
  double kept = 0;
  // Components with no spread carry no information about the properties.
  while (q < sigma.size() && sigma[q] > 1e-12 * std::max(1.0, sigma[0]) &&
         (total == 0 || kept < options.variance_kept * total)) {
    kept += sigma[q] * sigma[q];
    ++q;
  }
  q = std::min<int>(q, int(m) - 2);  // leave the regression over-determined
  if (q < 1) throw InputError("reduced template parameters: the fitted members do not vary");
  out.components = q;
  out.explained_variance = total > 0 ? kept / total : 1.0;
  const MatX V = svd.matrixV().leftCols(q);  // p x q
  const MatX T = P * V;                      // m x q scores

  // Least squares on the scores: y ≈ T B.
  const MatX B = T.colPivHouseholderQr().solve(Y);  // q x 2
  for (int j = 0; j < 2; ++j) {
    const double ss = Y.col(j).squaredNorm();
    out.regression_r2[j] = ss > 0 ? 1.0 - (Y.col(j) - T * B.col(j)).squaredNorm() / ss : 0.0;
  }

  // Directions: the regression gradients, then, when more are asked for than
  // there are properties, the leading principal components.
  std::vector<VecX> directions;
  auto add_orthogonal = [&](VecX d) {
    for (const VecX& e : directions) d -= d.dot(e) * e;
    const double n = d.norm();
    if (n > 1e-12) directions.push_back(d / n);
  };
  for (int j = 0; j < 2 && int(directions.size()) < options.reduced; ++j) add_orthogonal(V * B.col(j));
  for (int c = 0; c < q && int(directions.size()) < options.reduced; ++c) add_orthogonal(V.col(c));
  if (int(directions.size()) < options.reduced)
    throw InputError("reduced template parameters: only " + std::to_string(directions.size()) +
                     " independent directions among the fitted members, " + std::to_string(options.reduced) +
                     " asked for");

  const int r = options.reduced;
  out.property_slope = MatX::Zero(2, r);
  for (int j = 0; j < r; ++j) {
    const VecX s = P * directions[std::size_t(j)];
    double hi = s.maxCoeff(), lo = s.minCoeff();
    // A direction along which every member lies on one side still gets a
    // usable opposite extreme: the mirror of the other.
    if (hi <= 0) hi = -lo;
    if (lo >= 0) lo = -hi;
    out.plus.push_back(out.base + hi * directions[std::size_t(j)]);
    out.minus.push_back(out.base + lo * directions[std::size_t(j)]);
    // d(property)/d(r_j) for r_j > 0 by the linear model: the property
    // gradient in parameter space is V B.
    const VecX grad_logE = V * B.col(0), grad_nu = V * B.col(1);
    out.property_slope(0, j) = hi * grad_logE.dot(directions[std::size_t(j)]);
    out.property_slope(1, j) = hi * grad_nu.dot(directions[std::size_t(j)]);
  }
  return out;
}

VecX reduced_to_parameters(const ReducedTemplate& reduced, const std::vector<double>& r) {
  if (r.size() > reduced.plus.size())
    throw InputError("reduced parameters: " + std::to_string(r.size()) + " given, the family has " +
                     std::to_string(reduced.plus.size()));
  VecX p = reduced.base;
  for (std::size_t j = 0; j < r.size(); ++j) {
    if (!(r[j] >= -1.0 && r[j] <= 1.0))
      throw InputError("reduced parameter " + std::to_string(j + 1) + " is " + std::to_string(r[j]) +
                       "; it must lie in [-1, 1]");
    p += r[j] >= 0 ? VecX(r[j] * (reduced.plus[j] - reduced.base)) : VecX(-r[j] * (reduced.minus[j] - reduced.base));
  }
  return p;
}

}  // namespace msfab
