#include "dynamics/rigid_body.hpp"

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "dynamics/mass_matrix.hpp"

namespace msfab {

namespace {

Mat3 hat(const Vec3& a) {
  Mat3 A;
  A << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return A;
}

// Flips v so its largest-magnitude entry is positive (first index on ties).
Vec3 canonical_sign(const Vec3& v) {
  int k = 0;
  for (int i = 1; i < 3; ++i)
    if (std::abs(v(i)) > std::abs(v(k))) k = i;
  return v(k) < 0 ? Vec3(-v) : v;
}

// N x 3 view of a node-major 3N vector.
Eigen::Map<const NodeArray> as_nodes(const VecX& x) { return Eigen::Map<const NodeArray>(x.data(), x.size() / 3, 3); }

SpMat scalar_from(const SpMat& M, int num_nodes) {
  if (M.rows() == num_nodes && M.cols() == num_nodes) return M;
  if (M.rows() != 3 * num_nodes || M.cols() != 3 * num_nodes)
    throw InputError("rigid body: mass matrix is " + std::to_string(M.rows()) + " x " + std::to_string(M.cols()) +
                     ", expected N x N or 3N x 3N for N = " + std::to_string(num_nodes) + " nodes");
  std::vector<Eigen::Triplet<double, int>> triplets;
  for (int j = 0; j < M.outerSize(); j += 3)
    for (SpMat::InnerIterator it(M, j); it; ++it)
      if (it.row() % 3 == 0) triplets.emplace_back(it.row() / 3, j / 3, it.value());
  SpMat m(num_nodes, num_nodes);
  m.setFromTriplets(triplets.begin(), triplets.end());
  return m;
}

}  // namespace

PrincipalFrame principal_frame(const Mat3& inertia) {
  const Mat3 sym = 0.5 * (inertia + inertia.transpose());
  Eigen::SelfAdjointEigenSolver<Mat3> eig(sym);
  if (eig.info() != Eigen::Success) throw NumericalError("principal_frame: eigen-decomposition failed");
  PrincipalFrame f;
  f.moments = eig.eigenvalues();
  const Vec3 a1 = canonical_sign(eig.eigenvectors().col(0));
  const Vec3 a2 = canonical_sign(eig.eigenvectors().col(1));
  f.axes.col(0) = a1;
  f.axes.col(1) = a2;
  f.axes.col(2) = a1.cross(a2);
  return f;
}

RigidBody make_rigid_body(const SpMat& mass_matrix, const NodeArray& rest) {
  const int n = static_cast<int>(rest.rows());
  if (n == 0) throw InputError("rigid body: no nodes");
  RigidBody body;
  body.scalar_mass = scalar_from(mass_matrix, n);
  const MassProperties props = mass_properties(body.scalar_mass, rest);
  if (!(props.mass > 0) || !std::isfinite(props.mass))
    throw InputError("rigid body: total mass " + std::to_string(props.mass) + " is not positive");
  const PrincipalFrame frame = principal_frame(props.inertia());
  // A body whose smallest moment is zero is a point or a line: its rotation
  // about that line cannot be recovered from positions.
  if (!(frame.moments(0) > 1e-12 * frame.moments(2)))
    throw InputError("rigid body: degenerate inertia (principal moments " + std::to_string(frame.moments(0)) + ", " +
                     std::to_string(frame.moments(1)) + ", " + std::to_string(frame.moments(2)) + ")");
  body.mass = props.mass;
  body.rest_center = props.center;
  body.principal_axes = frame.axes;
  body.inertia = frame.moments;
  body.body_positions = (rest.rowwise() - props.center.transpose()) * frame.axes;
  return body;
}

RigidBody make_rigid_body(const SpMat& mass_matrix, const VecX& rest) {
  if (rest.size() % 3 != 0)
    throw InputError("rigid body: rest position vector has length " + std::to_string(rest.size()) +
                     ", not a multiple of 3");
  return make_rigid_body(mass_matrix, NodeArray(as_nodes(rest)));
}

RigidState project_to_rigid(const RigidBody& body, const VecX& q, const VecX& v) {
  const int n = body.num_nodes();
  if (q.size() != 3 * n || v.size() != 3 * n)
    throw InputError("project_to_rigid: positions (" + std::to_string(q.size()) + ") and velocities (" +
                     std::to_string(v.size()) + ") must have 3N = " + std::to_string(3 * n) + " entries");
  const auto X = as_nodes(q);
  const NodeArray P = body.scalar_mass * as_nodes(v);  // nodal momenta p_i = sum_j m_ij v_j
  const NodeArray MX = body.scalar_mass * X;

  RigidState s;
  // Row sums of m are the lumped masses: sum_i (M x)_i = sum_i r_i x_i.
  s.t = MX.colwise().sum().transpose() / body.mass;
  s.l = P.colwise().sum().transpose();
  for (int i = 0; i < n; ++i) s.pi += (X.row(i).transpose() - s.t).cross(P.row(i).transpose());

  // Cross-covariance sum_ij m_ij (x_i - t) B_j^T = sum_j ((M X)_j - r_j t) B_j^T
  // (m symmetric, r_j its row sums). Subtracting t is exact in theory (the
  // body positions are centred) but keeps far-flung bodies accurate.
  const VecX r = body.scalar_mass * VecX::Ones(n);
  const Mat3 H = (MX - r * s.t.transpose()).transpose() * body.body_positions;
  Eigen::JacobiSVD<Mat3> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 U = svd.matrixU();
  // Reflections are not motions: flip the direction of the smallest
  // singular value (the least constrained) when U V^T has det -1.
  if ((U * svd.matrixV().transpose()).determinant() < 0) U.col(2) *= -1;
  s.R = U * svd.matrixV().transpose();
  return s;
}

void project_to_fe(const RigidBody& body, const RigidState& s, VecX* q, VecX* v) {
  const int n = body.num_nodes();
  q->resize(3 * n);
  v->resize(3 * n);
  // The thesis writes v_i = l/m - R(x0_i - t0) x (I^-1 pi) with a body-frame
  // inverse inertia but the world-frame pi of Eq. B.22; the angular velocity
  // consistent with that pi is omega = R I^-1 R^T pi (world), which is what
  // makes the reconstructed field carry exactly the momentum pi.
  const Vec3 omega = world_angular_velocity(body, s);
  const Vec3 u = linear_velocity(body, s);
  for (int i = 0; i < n; ++i) {
    const Vec3 r = s.R * body.body_positions.row(i).transpose();
    q->segment<3>(3 * i) = s.t + r;
    v->segment<3>(3 * i) = u + omega.cross(r);
  }
}

Vec3 body_angular_momentum(const RigidState& s) { return s.R.transpose() * s.pi; }

Vec3 world_angular_velocity(const RigidBody& body, const RigidState& s) {
  return s.R * body_angular_momentum(s).cwiseQuotient(body.inertia);
}

Vec3 linear_velocity(const RigidBody& body, const RigidState& s) { return s.l / body.mass; }

double translational_kinetic_energy(const RigidBody& body, const RigidState& s) {
  return 0.5 * s.l.squaredNorm() / body.mass;
}

double rotational_kinetic_energy(const RigidBody& body, const RigidState& s) {
  const Vec3 m = body_angular_momentum(s);
  return 0.5 * m.dot(m.cwiseQuotient(body.inertia));
}

double kinetic_energy(const RigidBody& body, const RigidState& s) {
  return translational_kinetic_energy(body, s) + rotational_kinetic_energy(body, s);
}

Mat3 moser_veselov_increment(const Vec3& I, const Vec3& m, double h, const DmvOptions& options) {
  // Write Omega with its unit quaternion (s, w): Omega = Id + 2 s hat(w) + 2 hat(w)^2.
  // Using hat(w) D + D hat(w) = hat((tr D - D) w) = hat(I w) for D = J_d and
  // w w^T D - D w w^T = hat((D w) x w), the matrix equation becomes the
  // vector equation  2 s I w + 2 (D w) x w = h m.  In Cayley (Gibbs)
  // parameters c = w / s, s^2 = 1 / (1 + |c|^2), it is the quadratic
  //   G(c) = I c + (D c) x c - h/2 (1 + |c|^2) m = 0,
  // free of constraints for any turn below half a turn, solved by Newton.
  const Vec3 D = Vec3::Constant(0.5 * I.sum()) - I;
  const Vec3 half_hm = 0.5 * h * m;
  Vec3 c = half_hm.cwiseQuotient(I);  // small-angle guess: Omega ~ Id + h hat(I^-1 m)
  auto fail = [&](const std::string& why) {
    return NumericalError("Moser-Veselov step: " + why + " (h = " + std::to_string(h) +
                          ", |m| = " + std::to_string(m.norm()) + "); reduce the time step");
  };
  bool converged = false;
  for (int it = 0; it < options.max_iterations; ++it) {
    const Vec3 Dc = D.cwiseProduct(c);
    const Vec3 G = I.cwiseProduct(c) + Dc.cross(c) - (1 + c.squaredNorm()) * half_hm;
    // dG/dc = I + hat(D c) - hat(c) D - h m c^T.
    const Mat3 J = Mat3(I.asDiagonal()) + hat(Dc) - hat(c) * Mat3(D.asDiagonal()) - 2 * half_hm * c.transpose();
    const Vec3 dc = J.fullPivLu().solve(-G);
    if (!dc.allFinite()) throw fail("singular Newton system");
    c += dc;
    if (dc.norm() <= options.tolerance * c.norm() || dc.norm() == 0) {
      converged = true;
      break;
    }
  }
  if (!converged) throw fail("Newton did not converge in " + std::to_string(options.max_iterations) + " iterations");
  // Omega = Id + 2/(1+|c|^2) (hat(c) + hat(c)^2), the Cayley transform.
  const Mat3 C = hat(c);
  return Mat3::Identity() + (2 / (1 + c.squaredNorm())) * (C + C * C);
}

void dmv_step(const RigidBody& body, const Vec3& g, double h, RigidState* state, const DmvOptions& options) {
  RigidState& s = *state;
  // Uniform gravity: the centre of mass moves on the exact parabola.
  s.t += h * s.l / body.mass + 0.5 * h * h * g;
  s.l += h * body.mass * g;
  // Torque-free rotation. The body momentum update m <- Omega^T m is implied:
  // R Omega (Omega^T R^T pi) = pi, so keeping pi fixed is the same map and
  // conserves the world angular momentum to the last bit.
  const Mat3 Omega = moser_veselov_increment(body.inertia, body_angular_momentum(s), h, options);
  s.R = s.R * Omega;
  // One Newton-Schulz sweep keeps R on SO(3) against accumulated round-off
  // (a second-order correction, invisible at the integrator's accuracy).
  s.R = s.R * (1.5 * Mat3::Identity() - 0.5 * s.R.transpose() * s.R);
}

}  // namespace msfab
