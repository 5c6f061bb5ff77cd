#include "dynamics/contact_problem.hpp"

#include <algorithm>
#include <cmath>

namespace msfab {

Mat3 contact_frame(const Vec3& n) {
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (std::abs(n(a)) < std::abs(n(axis))) axis = a;
  Vec3 t1 = Vec3::Unit(axis) - n(axis) * n;
  t1.normalize();
  Mat3 frame;
  frame.col(0) = n;
  frame.col(1) = t1;
  frame.col(2) = n.cross(t1);
  return frame;
}

Eigen::Vector2d minimize_quadratic_in_disk(const Eigen::Matrix2d& A, const Eigen::Vector2d& c, double radius) {
  if (!(radius > 0)) return Eigen::Vector2d::Zero();
  const Eigen::Vector2d inside = -A.ldlt().solve(c);
  if (inside.norm() <= radius) return inside;
  // On the boundary: x(nu) = -(A + nu I)^{-1} c with |x(nu)| = radius, nu > 0.
  // |x(nu)| decreases in nu; |x(|c|/radius)| <= radius brackets the root.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(A);
  const Eigen::Vector2d lambda = eig.eigenvalues();
  const Eigen::Vector2d ct = eig.eigenvectors().transpose() * c;
  // g(nu) = 1/radius - 1/|x(nu)| falls from g(0) > 0 to -inf and is
  // nearly linear, so safeguarded Newton converges in a few steps where
  // bisection needs fifty (this runs once per contact per Gauss-Seidel sweep).
  auto g_and_slope = [&](double nu, double* slope) {
    const double a0 = ct(0) / (lambda(0) + nu), a1 = ct(1) / (lambda(1) + nu);
    const double n2 = a0 * a0 + a1 * a1, n = std::sqrt(n2);
    const double dn2 = -2 * (a0 * a0 / (lambda(0) + nu) + a1 * a1 / (lambda(1) + nu));  // d|x|^2 / dnu
    *slope = 0.5 * dn2 / (n2 * n);
    return 1.0 / radius - 1.0 / n;
  };
  double lo = 0.0, hi = c.norm() / radius, nu = 0.0;
  for (int it = 0; it < 100; ++it) {
    double slope;
    const double g = g_and_slope(nu, &slope);
    (g > 0 ? lo : hi) = nu;
    double next = slope < 0 ? nu - g / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool done = std::abs(next - nu) <= 1e-15 * next || hi - lo <= 1e-15 * hi;
    nu = next;
    if (done) break;
  }
  Eigen::Vector2d x = -eig.eigenvectors() * Eigen::Vector2d(ct(0) / (lambda(0) + nu), ct(1) / (lambda(1) + nu));
  // Land exactly on the cone boundary so |p_T| <= mu p_n holds to round-off.
  const double nx = x.norm();
  if (nx > 0) x *= radius / nx;
  return x;
}

ContactSolveResult solve_contact_problem(const ContactProblem& pb, const VecX& warm,
                                         const ContactSolveOptions& options) {
  const int m = static_cast<int>(pb.gap0.size());
  ContactSolveResult result;
  result.p = warm.size() == 3 * m ? warm : VecX::Zero(3 * m);
  VecX& p = result.p;
  // u = u_free + W p, kept current as p changes.
  VecX u = pb.u_free + pb.W * p;
  const double velocity_scale = 2.0 / pb.h;

  for (int sweep = 1; sweep <= options.max_sweeps; ++sweep) {
    double max_change = 0, max_p = 0;
    for (int k = 0; k < m; ++k) {
      const int i = 3 * k;
      const Vec3 old = p.segment<3>(i);
      // Normal: exact complementarity solve with the others held fixed.
      const double wnn = pb.W(i, i);
      double pn = std::max(0.0, old(0) - (pb.gap0[k] + u(i)) / wnn);
      Eigen::Vector2d pt(old(1), old(2));
      if (pn != old(0)) u.noalias() += pb.W.col(i) * (pn - old(0));
      // Friction: the disk-constrained maximal-dissipation problem.
      if (pb.mu[k] > 0 && pn > 0) {
        const Eigen::Matrix2d A = velocity_scale * pb.W.block<2, 2>(i + 1, i + 1);
        const Eigen::Vector2d u_t_without = u.segment<2>(i + 1) - pb.W.block<2, 2>(i + 1, i + 1) * pt;
        const Eigen::Vector2d w0 = velocity_scale * u_t_without - pb.tangential_velocity_start.segment<2>(2 * k);
        pt = minimize_quadratic_in_disk(A, w0, pb.mu[k] * pn);
      } else {
        pt.setZero();
      }
      const Eigen::Vector2d dpt = pt - Eigen::Vector2d(old(1), old(2));
      if (dpt(0) != 0) u.noalias() += pb.W.col(i + 1) * dpt(0);
      if (dpt(1) != 0) u.noalias() += pb.W.col(i + 2) * dpt(1);
      p.segment<3>(i) = Vec3(pn, pt(0), pt(1));
      max_change = std::max(max_change, (p.segment<3>(i) - old).cwiseAbs().maxCoeff());
      max_p = std::max(max_p, p.segment<3>(i).cwiseAbs().maxCoeff());
    }
    result.sweeps = sweep;
    result.max_change = max_p > 0 ? max_change / max_p : 0.0;
    if (result.max_change <= options.tolerance) {
      result.converged = true;
      break;
    }
  }
  return result;
}

}  // namespace msfab
