// Free-flight rigid model (thesis App. B.2): mass properties of a voxel box
// against the analytic box inertia, the FE <-> SE(3) projections, and the
// Moser-Veselov integrator against conservation laws, the analytic
// symmetric top and an independent fine-step RK4 reference.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

#include "core/errors.hpp"
#include "dynamics/mass_matrix.hpp"
#include "dynamics/rigid_body.hpp"
#include "fem/voxel_grid.hpp"
#include "material/neo_hookean.hpp"

using namespace msfab;

namespace {

constexpr double kVoxel = 0.01;  // m
constexpr double kRho = 1200.0;  // kg/m^3

// A 3x2x1-voxel box.
HexMesh box_mesh() {
  VoxelGrid grid(3, 2, 1, kVoxel, 1);
  grid.origin = Vec3(0.2, -0.1, 0.05);
  const std::vector<MaterialPtr> palette = {nullptr, std::make_shared<NeoHookean>(1e6, 0.3)};
  return build_voxel_mesh(grid, palette).mesh;
}

SpMat box_scalar_mass(const HexMesh& mesh) {
  return scalar_mass_matrix(mesh, std::vector<double>(mesh.num_elements(), kRho));
}

Mat3 rotation(double angle, const Vec3& axis) { return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix(); }

Mat3 hat(const Vec3& a) {
  Mat3 A;
  A << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return A;
}

double orthogonality_error(const Mat3& R) { return (R.transpose() * R - Mat3::Identity()).norm(); }

// Momenta of an FE state measured with the 3N x 3N mass matrix.
struct Momenta {
  Vec3 linear = Vec3::Zero(), angular = Vec3::Zero(), center = Vec3::Zero();
  double kinetic = 0;
};
Momenta fe_momenta(const SpMat& M3, double mass, const VecX& q, const VecX& v) {
  Momenta out;
  const VecX p = M3 * v;
  const int n = static_cast<int>(q.size() / 3);
  // Centre of mass: M 1_x picks the lumped masses for the x components.
  VecX ex = VecX::Zero(3 * n), ey = ex, ez = ex;
  for (int i = 0; i < n; ++i) ex(3 * i) = ey(3 * i + 1) = ez(3 * i + 2) = 1;
  out.center = Vec3((M3 * ex).dot(q), (M3 * ey).dot(q), (M3 * ez).dot(q)) / mass;
  for (int i = 0; i < n; ++i) {
    out.linear += p.segment<3>(3 * i);
    out.angular += (q.segment<3>(3 * i) - out.center).cross(p.segment<3>(3 * i));
  }
  out.kinetic = 0.5 * v.dot(p);
  return out;
}

// A rigid FE state: rest nodes moved by x = t + Q (X - c0), spinning at omega.
void rigid_fe_state(const HexMesh& mesh, const Vec3& c0, const Mat3& Q, const Vec3& t, const Vec3& u, const Vec3& omega,
                    VecX* q, VecX* v) {
  const int n = mesh.num_nodes();
  q->resize(3 * n);
  v->resize(3 * n);
  for (int i = 0; i < n; ++i) {
    const Vec3 r = Q * (mesh.nodes.row(i).transpose() - c0);
    q->segment<3>(3 * i) = t + r;
    v->segment<3>(3 * i) = u + omega.cross(r);
  }
}

// A body with given principal moments (only mass and inertia drive DMV).
RigidBody abstract_body(double mass, const Vec3& moments) {
  RigidBody b;
  b.mass = mass;
  b.inertia = moments;
  return b;
}

// Fine-step classical RK4 on (R, body momentum m) for R' = R hat(I^-1 m),
// m' = m x I^-1 m: an independent reference for the torque-free body.
void rk4_reference(const Vec3& I, double T, int steps, Mat3* R, Vec3* m) {
  const double h = T / steps;
  auto f = [&](const Mat3& Rs, const Vec3& ms, Mat3* dR, Vec3* dm) {
    const Vec3 w = ms.cwiseQuotient(I);
    *dR = Rs * hat(w);
    *dm = ms.cross(w);
  };
  for (int k = 0; k < steps; ++k) {
    Mat3 k1R, k2R, k3R, k4R;
    Vec3 k1m, k2m, k3m, k4m;
    f(*R, *m, &k1R, &k1m);
    f(*R + 0.5 * h * k1R, *m + 0.5 * h * k1m, &k2R, &k2m);
    f(*R + 0.5 * h * k2R, *m + 0.5 * h * k2m, &k3R, &k3m);
    f(*R + h * k3R, *m + h * k3m, &k4R, &k4m);
    *R += h / 6 * (k1R + 2 * k2R + 2 * k3R + k4R);
    *m += h / 6 * (k1m + 2 * k2m + 2 * k3m + k4m);
  }
}

RigidState run_dmv(const RigidBody& body, RigidState s, double T, int steps, const Vec3& g = Vec3::Zero()) {
  for (int k = 0; k < steps; ++k) dmv_step(body, g, T / steps, &s);
  return s;
}

}  // namespace

TEST(RigidBody, VoxelBoxMassAndPrincipalInertiaAreAnalytic) {
  const HexMesh mesh = box_mesh();
  const RigidBody body = make_rigid_body(box_scalar_mass(mesh), mesh.nodes);
  const double a = 3 * kVoxel, b = 2 * kVoxel, c = kVoxel;
  const double m = kRho * a * b * c;
  EXPECT_NEAR(body.mass, m, 1e-12 * m);
  EXPECT_LT((body.rest_center - (Vec3(0.2, -0.1, 0.05) + 0.5 * Vec3(a, b, c))).norm(), 1e-12 * a);
  // Ascending: about the long x axis, then y, then z.
  const Vec3 expected(m * (b * b + c * c) / 12, m * (a * a + c * c) / 12, m * (a * a + b * b) / 12);
  const double scale = expected.maxCoeff();
  EXPECT_LT((body.inertia - expected).norm(), 1e-12 * scale);
  EXPECT_LT((body.principal_axes - Mat3::Identity()).norm(), 1e-12);
  // The body positions are the rest nodes about the centre in that frame.
  EXPECT_LT((body.body_positions.row(0).transpose() + 0.5 * Vec3(a, b, c)).norm(), 1e-12 * a);
}

TEST(RigidBody, PrincipalFrameFollowsARotatedBodyAndAcceptsTheDofMatrix) {
  HexMesh mesh = box_mesh();
  const Mat3 Q = rotation(0.8, Vec3(1, -2, 0.5));
  const Vec3 shift(-1.0, 2.0, 0.3);
  for (int i = 0; i < mesh.num_nodes(); ++i)
    mesh.nodes.row(i) = (Q * mesh.nodes.row(i).transpose() + shift).transpose();
  const SpMat m = box_scalar_mass(mesh);
  const RigidBody body = make_rigid_body(m, mesh.nodes);
  const RigidBody body3 =
      make_rigid_body(expand_to_dofs(m), VecX(Eigen::Map<const VecX>(mesh.nodes.data(), 3 * mesh.num_nodes())));
  const double scale = body.inertia.maxCoeff();
  const double mass = kRho * 6 * std::pow(kVoxel, 3);
  const Vec3 expected = mass * kVoxel * kVoxel * Vec3(5, 10, 13) / 12;
  EXPECT_LT((body.inertia - expected).norm(), 1e-12 * scale);
  EXPECT_NEAR(body.principal_axes.determinant(), 1.0, 1e-14);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(std::abs(body.principal_axes.col(k).dot(Q.col(k))), 1.0, 1e-12);
  const Mat3 I0 = mass_properties(m, mesh.nodes).inertia();
  EXPECT_LT((body.principal_axes * body.inertia.asDiagonal() * body.principal_axes.transpose() - I0).norm(),
            1e-12 * scale);
  EXPECT_NEAR(body3.mass, body.mass, 1e-15 * body.mass);
  EXPECT_LT((body3.principal_axes - body.principal_axes).norm(), 1e-12);
  EXPECT_LT((body3.body_positions - body.body_positions).norm(), 1e-14);
  EXPECT_THROW(make_rigid_body(m, NodeArray(mesh.nodes.topRows(5))), InputError);
}

TEST(RigidBody, ProjectionRecoversARigidMotionAndRoundTrips) {
  HexMesh mesh = box_mesh();
  const Mat3 Q0 = rotation(0.4, Vec3(0.3, 1, -0.7));  // rest pose not axis aligned
  for (int i = 0; i < mesh.num_nodes(); ++i) mesh.nodes.row(i) = (Q0 * mesh.nodes.row(i).transpose()).transpose();
  const SpMat m = box_scalar_mass(mesh);
  const RigidBody body = make_rigid_body(m, mesh.nodes);
  const Mat3 I0 = mass_properties(m, mesh.nodes).inertia();

  // Includes a turn by more than a half turn's worth about a skew axis.
  const Mat3 Q = rotation(2.6, Vec3(-0.2, 0.9, 0.4));
  const Vec3 t(0.5, -0.3, 1.2), u(0.7, 0.1, -2.0), omega(3.0, -11.0, 5.0);
  VecX q, v;
  rigid_fe_state(mesh, body.rest_center, Q, t, u, omega, &q, &v);
  const RigidState s = project_to_rigid(body, q, v);

  const Vec3 l = body.mass * u;
  const Vec3 pi = Q * I0 * Q.transpose() * omega;  // world inertia about t
  EXPECT_LT((s.R - Q * body.principal_axes).norm(), 1e-12);
  EXPECT_LT((s.t - t).norm(), 1e-12 * t.norm());
  EXPECT_LT((s.l - l).norm(), 1e-12 * l.norm());
  EXPECT_LT((s.pi - pi).norm(), 1e-12 * pi.norm());
  EXPECT_LT((world_angular_velocity(body, s) - omega).norm(), 1e-12 * omega.norm());
  EXPECT_LT(orthogonality_error(s.R), 1e-14);
  EXPECT_NEAR(s.R.determinant(), 1.0, 1e-14);

  VecX q2, v2;
  project_to_fe(body, s, &q2, &v2);
  const double dq = (q2 - q).cwiseAbs().maxCoeff(), dv = (v2 - v).cwiseAbs().maxCoeff();
  std::printf("rigid round trip: max |dq| = %.2e m, max |dv| = %.2e m/s\n", dq, dv);
  EXPECT_LT(dq, 1e-12 * t.norm());
  EXPECT_LT(dv, 1e-12 * v.cwiseAbs().maxCoeff());
  // The rigid kinetic energy equals 1/2 v^T M v of the FE field.
  const Momenta fe = fe_momenta(expand_to_dofs(m), body.mass, q, v);
  EXPECT_NEAR(kinetic_energy(body, s), fe.kinetic, 1e-12 * fe.kinetic);
  EXPECT_NEAR(translational_kinetic_energy(body, s), 0.5 * body.mass * u.squaredNorm(), 1e-12 * fe.kinetic);
}

TEST(RigidBody, HandOffOfADeformedStatePreservesMomentaExactly) {
  const HexMesh mesh = box_mesh();
  const SpMat m = box_scalar_mass(mesh);
  const SpMat M3 = expand_to_dofs(m);
  const RigidBody body = make_rigid_body(M3, mesh.nodes);
  VecX q, v;
  rigid_fe_state(mesh, body.rest_center, rotation(1.1, Vec3(1, 1, 0)), Vec3(0, 0, 0.4), Vec3(0.3, 0, 1.5),
                 Vec3(-4, 2, 9), &q, &v);
  // A non-rigid perturbation: a few percent of the voxel size, and
  // deformation velocities of the size of the rigid ones.
  for (int i = 0; i < q.size(); ++i) {
    q(i) += 0.03 * kVoxel * std::sin(1.7 * i + 0.3);
    v(i) += 0.5 * std::cos(2.3 * i);
  }
  const Momenta before = fe_momenta(M3, body.mass, q, v);
  const RigidState s = project_to_rigid(body, q, v);
  EXPECT_LT((s.l - before.linear).norm(), 1e-13 * before.linear.norm());
  EXPECT_LT((s.pi - before.angular).norm(), 1e-13 * before.angular.norm());
  EXPECT_LT((s.t - before.center).norm(), 1e-14);
  EXPECT_LT(orthogonality_error(s.R), 1e-14);

  VecX q2, v2;
  project_to_fe(body, s, &q2, &v2);
  const Momenta after = fe_momenta(M3, body.mass, q2, v2);
  const double dl = (after.linear - s.l).norm() / s.l.norm(), dpi = (after.angular - s.pi).norm() / s.pi.norm();
  std::printf("deformed hand-off: relative momentum change linear %.2e, angular %.2e; centre moved %.2e m\n", dl, dpi,
              (after.center - s.t).norm());
  EXPECT_LT(dl, 1e-13);
  EXPECT_LT(dpi, 1e-12);
  EXPECT_LT((after.center - s.t).norm(), 1e-14);
  EXPECT_NEAR(after.kinetic, kinetic_energy(body, s), 1e-12 * after.kinetic);
  // The fitted pose is close to, but not, the deformed one.
  const double dq = (q2 - q).cwiseAbs().maxCoeff();
  EXPECT_GT(dq, 1e-3 * kVoxel);
  EXPECT_LT(dq, 0.1 * kVoxel);
}

TEST(RigidBody, MoserVeselovIncrementSolvesItsEquation) {
  const Vec3 I(0.7, 1.3, 1.8);
  const Vec3 D = Vec3::Constant(0.5 * I.sum()) - I;
  const Vec3 m(2.0, -3.0, 1.5);
  for (const double h : {1e-4, 0.05, 0.2}) {  // the last turns by 0.86 rad
    const Mat3 Om = moser_veselov_increment(I, m, h);
    const Mat3 lhs = Om * D.asDiagonal() - D.asDiagonal() * Om.transpose();
    EXPECT_LT((lhs - h * hat(m)).norm(), 1e-14 * h * m.norm()) << "h = " << h;
    EXPECT_LT(orthogonality_error(Om), 1e-15);
    EXPECT_NEAR(Om.determinant(), 1.0, 1e-15);
  }
  EXPECT_LT((moser_veselov_increment(I, Vec3::Zero(), 0.1) - Mat3::Identity()).norm(), 1e-300);
  // Beyond h |m| ~ 1.1 this body's equation has no solution near Id.
  EXPECT_THROW(moser_veselov_increment(I, m, 0.3), NumericalError);
  EXPECT_THROW(moser_veselov_increment(I, m, 100.0), NumericalError);
}

TEST(RigidBody, DmvTumblingBodyConservesEnergyAndMomentum) {
  // Spin near the unstable intermediate axis: the body flips repeatedly. The
  // Moser-Veselov map conserves the energy exactly (not to O(h^2)), so the
  // bound holds for a coarse step as well as a fine one.
  const RigidBody body = abstract_body(2.0, Vec3(0.5, 1.0, 1.6));
  for (const double h : {0.01, 0.1}) {  // 0.03 and 0.3 rad per step
    RigidState s;
    s.R = rotation(0.3, Vec3(1, 2, 3));
    s.pi = s.R * Vec3(0.02, 3.0, 0.05);
    const Vec3 pi0 = s.pi;
    const double E0 = rotational_kinetic_energy(body, s);
    const int steps = 10000;
    double max_dE = 0, max_orth = 0, min_m2 = 1e300;
    for (int k = 0; k < steps; ++k) {
      dmv_step(body, Vec3::Zero(), h, &s);
      max_dE = std::max(max_dE, std::abs(rotational_kinetic_energy(body, s) - E0) / E0);
      max_orth = std::max(max_orth, orthogonality_error(s.R));
      min_m2 = std::min(min_m2, body_angular_momentum(s)(1));
    }
    std::printf(
        "DMV tumbling, h = %g, %d steps: max relative energy error %.2e, |R^T R - 1| <= %.2e, "
        "|dpi| = %.2e\n",
        h, steps, max_dE, max_orth, (s.pi - pi0).norm());
    EXPECT_LT(min_m2, -2.5);  // it did tumble: the body momentum flipped
    EXPECT_LT(max_dE, 1e-12);
    EXPECT_LT(max_orth, 1e-14);
    EXPECT_LT((s.pi - pi0).norm(), 1e-15 * pi0.norm());
    EXPECT_NEAR(body_angular_momentum(s).norm(), pi0.norm(), 1e-13 * pi0.norm());
  }
}

TEST(RigidBody, DmvMatchesTheSymmetricTopAtSecondOrder) {
  // I1 = I2: R(t) = exp(t hat(pi) / I1) R0 exp(t (1/I3 - 1/I1) m3 hat(e3)).
  const Vec3 I(0.8, 0.8, 1.4);
  const RigidBody body = abstract_body(1.0, I);
  RigidState s0;
  s0.R = rotation(0.7, Vec3(0.2, -1, 0.4));
  s0.pi = Vec3(1.0, 2.0, -0.5);
  const double T = 2.0;
  const double m3 = (s0.R.transpose() * s0.pi)(2);
  const Mat3 exact =
      rotation(T * s0.pi.norm() / I(0), s0.pi) * s0.R * rotation(T * (1 / I(2) - 1 / I(0)) * m3, Vec3::UnitZ());
  double prev = 0;
  for (const int steps : {50, 100, 200, 400}) {
    const double err = (run_dmv(body, s0, T, steps).R - exact).norm();
    if (prev > 0) {
      std::printf("symmetric top: %d steps, error %.3e, order %.3f\n", steps, err, std::log2(prev / err));
      EXPECT_NEAR(std::log2(prev / err), 2.0, 0.05);
    }
    prev = err;
  }
  EXPECT_LT(prev, 1e-3);
}

TEST(RigidBody, DmvMatchesAFineRk4ReferenceAtSecondOrder) {
  const Vec3 I(0.6, 1.1, 1.5);
  const RigidBody body = abstract_body(1.0, I);
  RigidState s0;
  s0.R = rotation(-0.5, Vec3(1, 0.3, 0.2));
  s0.pi = Vec3(0.9, -1.4, 0.6);
  const double T = 1.5;
  Mat3 R_ref = s0.R;
  Vec3 m_ref = s0.R.transpose() * s0.pi;
  rk4_reference(I, T, 20000, &R_ref, &m_ref);
  double prev = 0;
  for (const int steps : {40, 80, 160, 320}) {
    const RigidState s = run_dmv(body, s0, T, steps);
    const double err = (s.R - R_ref).norm() + (body_angular_momentum(s) - m_ref).norm() / m_ref.norm();
    if (prev > 0) {
      std::printf("asymmetric body vs RK4: %d steps, error %.3e, order %.3f\n", steps, err, std::log2(prev / err));
      EXPECT_NEAR(std::log2(prev / err), 2.0, 0.1);
    }
    prev = err;
  }
}

TEST(RigidBody, FreeFallFollowsTheParabolaExactly) {
  const RigidBody body = abstract_body(0.35, Vec3(1e-4, 2e-4, 2.5e-4));
  RigidState s;
  s.t = Vec3(0.1, -0.2, 0.5);
  const Vec3 v0(0.8, 0.3, 2.5);
  s.l = body.mass * v0;
  s.pi = Vec3(2e-3, -1e-3, 4e-3);  // spinning does not move the centre
  const Vec3 g(0, 0, -9.81);
  const double h = 1e-3;
  const int steps = 700;
  const Vec3 t0 = s.t;
  for (int k = 0; k < steps; ++k) dmv_step(body, g, h, &s);
  const double T = steps * h;
  const Vec3 t_exact = t0 + v0 * T + 0.5 * g * T * T;
  const Vec3 v_exact = v0 + g * T;
  std::printf("free fall after %.2f s: centre error %.2e m, velocity error %.2e m/s\n", T, (s.t - t_exact).norm(),
              (linear_velocity(body, s) - v_exact).norm());
  EXPECT_LT((s.t - t_exact).norm(), 1e-13);
  EXPECT_LT((linear_velocity(body, s) - v_exact).norm(), 1e-13);
}
