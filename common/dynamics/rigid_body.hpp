#pragma once
// Free-flight rigid model of one body (thesis App. B.2, Eq. B.22-B.23, §4.5.2).
// When a body's elastic energy has died out in flight, its FE state is
// projected onto SE(3) with momenta, stepped with the discrete Moser-Veselov
// (DMV) integrator, and mapped back to nodal positions and velocities at the
// next contact.
//
// Frames: the body frame is the principal frame of the rest configuration,
// centred at the rest centre of mass c0 with axes A (columns, right-handed),
// so a material point with rest position X sits at B = A^T (X - c0) in the
// body frame and, in a rigid state, at x = t + R B in the world.
#include "fem/hex_mesh.hpp"

namespace msfab {

// Principal axes of a symmetric positive semidefinite inertia tensor:
// inertia = axes diag(moments) axes^T, moments ascending. Convention (so
// equal inputs give equal frames): axes 1 and 2 have their largest-magnitude
// entry positive (the first such on ties), axis 3 = axis 1 x axis 2.
struct PrincipalFrame {
  Mat3 axes = Mat3::Identity();
  Vec3 moments = Vec3::Zero();
};
PrincipalFrame principal_frame(const Mat3& inertia);

struct RigidBody {
  double mass = 0;
  Vec3 rest_center = Vec3::Zero();         // c0
  Mat3 principal_axes = Mat3::Identity();  // A, det +1
  Vec3 inertia = Vec3::Zero();             // body-frame diagonal inertia, ascending
  SpMat scalar_mass;                       // N x N consistent mass (m_ij)
  NodeArray body_positions;                // rest nodes in the body frame, A^T (X_i - c0)
  int num_nodes() const { return static_cast<int>(body_positions.rows()); }
};

// Mass properties from the consistent mass matrix, either the scalar N x N
// one or its 3N x 3N expansion m_ij I_3 (the scalar entries are read back
// from the x-x blocks). rest is N x 3, or node-major 3N. InputError when the
// sizes disagree, the mass is not positive or the body is degenerate (a zero
// principal moment: a rigid frame cannot be fitted to a line or a point).
RigidBody make_rigid_body(const SpMat& mass_matrix, const NodeArray& rest);
RigidBody make_rigid_body(const SpMat& mass_matrix, const VecX& rest);

// R: body -> world rotation. t: centre of mass (world). pi: angular momentum
// about t in the WORLD frame (what Eq. B.22 sums; constant in free flight).
// l: linear momentum (world).
struct RigidState {
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  Vec3 pi = Vec3::Zero();
  Vec3 l = Vec3::Zero();
};

// Eq. B.22 with the consistent mass M: p = M v, l = sum p_i, t = centre of
// mass of q, pi = sum (x_i - t) x p_i (the exact momenta of the interpolated
// velocity field), and R = the rotation of SO(3) minimising
// \int rho |x(X) - t - R B(X)|^2, i.e. the polar factor of the mass-weighted
// cross-covariance sum_ij m_ij (x_i - t) B_j^T (reflection removed).
// q, v: node-major 3N. InputError on wrong sizes.
RigidState project_to_rigid(const RigidBody& body, const VecX& q, const VecX& v);

// Eq. B.23: x_i = t + R B_i, v_i = l/m + omega x (x_i - t) with the world
// angular velocity omega = R I^-1 R^T pi. The result carries exactly the
// momenta l and pi of the state (measured with M), and is the identity after
// project_to_rigid for rigid FE states. q, v are resized to 3N.
void project_to_fe(const RigidBody& body, const RigidState& state, VecX* q, VecX* v);

// Body-frame angular momentum R^T pi and velocities.
Vec3 body_angular_momentum(const RigidState& state);
Vec3 world_angular_velocity(const RigidBody& body, const RigidState& state);
Vec3 linear_velocity(const RigidBody& body, const RigidState& state);

double translational_kinetic_energy(const RigidBody& body, const RigidState& state);  // |l|^2 / 2m
double rotational_kinetic_energy(const RigidBody& body, const RigidState& state);     // pi_b . I^-1 pi_b / 2
double kinetic_energy(const RigidBody& body, const RigidState& state);

// Newton solve of the Moser-Veselov equation for the body-frame increment.
struct DmvOptions {
  double tolerance = 1e-14;  // on the Newton update, relative to its iterate
  int max_iterations = 30;
};

// The orthogonal Omega with  Omega J_d - J_d Omega^T = h hat(m),
// J_d = tr(I)/2 Id - I, for principal moments I and body angular momentum m;
// the step is R <- R Omega, m <- Omega^T m. NumericalError when Newton fails
// or the step would turn the body by half a turn or more (h far too large).
Mat3 moser_veselov_increment(const Vec3& inertia, const Vec3& body_momentum, double h, const DmvOptions& options = {});

// One DMV step of length h under uniform gravity g acting at the centre of
// mass. Translation is the exact parabola; the rotation is the Moser-Veselov
// map, which keeps the world angular momentum pi fixed (gravity exerts no
// torque about t) and conserves the rotational kinetic energy to round-off
// at any step size; it is second-order accurate in the pose. Uses only
// body.mass and body.inertia.
void dmv_step(const RigidBody& body, const Vec3& gravity, double h, RigidState* state, const DmvOptions& options = {});

}  // namespace msfab
