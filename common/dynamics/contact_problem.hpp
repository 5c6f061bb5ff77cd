#pragma once
// The frictional contact problem of one Newton iterate (thesis B.13-B.18),
// written in the contact coordinates of each contact k: one normal n_k and
// two tangents (t1_k, t2_k) at a node.
//
// With G = [n_1 t1_1 t2_1 ... ] the generalized contact directions (B.5:
// a node-vertex contact maps to the node's three DOFs) and H the Newmark
// Jacobian, the step is delta = delta_free + H^{-1} G p, where p holds the
// contact impulses scaled by h^2/2 (p = h^2/2 (alpha, beta)). So the local
// displacements are u = G^T delta_free + W p with the Delassus matrix
// W = G^T H^{-1} G, and each contact must satisfy
//   normal:   0 <= p_n  _|_  gap0 + u_n >= 0                       (B.12/B.14)
//   friction: p_T = argmin over |p_T| <= mu p_n of p_T . w_T       (B.4/B.14)
// where w_T = (2/h) u_T - T^T v^t is the end-of-step tangential velocity.
// Maximal dissipation with w_T depending on p_T is the trust-region problem
//   min 1/2 p_T^T (2/h W_TT) p_T + w_T0^T p_T  s.t. |p_T| <= mu p_n,
// whose KKT conditions say exactly: stick (w_T = 0) inside the cone, or
// slide with p_T antiparallel to w_T on its boundary. Gauss-Seidel over the
// contacts (B.17) solves each contact's normal and tangential parts in turn.
#include <vector>

#include "core/types.hpp"

namespace msfab {

struct ContactProblem {
  double h = 0;                    // time step
  MatX W;                          // 3m x 3m Delassus matrix, contact-major (n, t1, t2)
  VecX u_free;                     // 3m local displacements of delta_free
  std::vector<double> gap0;        // m gaps at the start of the step
  std::vector<double> mu;          // m friction coefficients (0 = frictionless)
  VecX tangential_velocity_start;  // 2m: T_k^T v^t
};

struct ContactSolveOptions {
  int max_sweeps = 2000;
  // Sweeps stop when no impulse changed by more than this fraction of the
  // largest impulse.
  double tolerance = 1e-11;
};

struct ContactSolveResult {
  VecX p;  // 3m impulses (scaled by h^2/2)
  int sweeps = 0;
  bool converged = false;
  double max_change = 0;  // relative change of the last sweep
};

// Projected Gauss-Seidel with the exact two-dimensional friction update.
// `warm` (size 3m or empty) is the starting guess.
ContactSolveResult solve_contact_problem(const ContactProblem& problem, const VecX& warm,
                                         const ContactSolveOptions& options = {});

// min 1/2 x^T A x + c^T x  subject to |x| <= radius, A 2x2 symmetric
// positive definite (the trust-region subproblem in two dimensions, solved
// through the eigen-decomposition of A and bisection on the multiplier).
Eigen::Vector2d minimize_quadratic_in_disk(const Eigen::Matrix2d& A, const Eigen::Vector2d& c, double radius);

// An orthonormal tangent pair for a unit normal: columns (n, t1, t2) form a
// right-handed frame; t1 is the normalized projection of the coordinate axis
// least aligned with n, so the frame is deterministic.
Mat3 contact_frame(const Vec3& normal);

}  // namespace msfab
