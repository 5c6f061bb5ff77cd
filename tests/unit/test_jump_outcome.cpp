// Jump measures on synthetic trajectories: twist about an axis, unwrapping
// through the rotation vector's wrap at pi, lift-off and landing with
// contact flicker, crossing height, upright test.
#include <gtest/gtest.h>

#include <cmath>

#include "core/errors.hpp"
#include "dynamics/jump_outcome.hpp"

namespace msfab {
namespace {

// The rotation vector of a rotation by `angle` about y, as the run records
// it: Eigen's AngleAxis gives angles in [0, pi], so past pi the axis flips.
Vec3 recorded_rotation(double angle, const Vec3& axis = Vec3::UnitY()) {
  const Eigen::AngleAxisd r(Mat3(Eigen::AngleAxisd(angle, axis.normalized())));
  return r.angle() * r.axis();
}

// A ballistic jump: on the ground until t0, airborne until t1 spinning at
// `spin` rad/s about y, then resting; sampled every h, starting with one
// quasistatic sample.
Trajectory ballistic(double t0, double t1, double spin, double h = 1e-4, double end = 0.3) {
  Trajectory t;
  TrajectorySample pressed;
  pressed.phase = SimulationPhase::kQuasistatic;
  pressed.contacts = pressed.active_contacts = 0;  // the press records no step report
  t.samples.push_back(pressed);
  const double vx = 0.4, vz = 9.81 * (t1 - t0) / 2;
  for (int k = 0; k * h <= end + 1e-12; ++k) {
    const double time = k * h;
    TrajectorySample s;
    s.time = time;
    const double tf = std::clamp(time, t0, t1) - t0;  // time in flight so far
    s.center_of_mass = Vec3(0.02 + vx * tf, 0.005, 0.005 + vz * tf - 0.5 * 9.81 * tf * tf);
    s.rotation = recorded_rotation(spin * tf);
    s.active_contacts = s.contacts = (time > t0 && time < t1) ? 0 : 10;
    s.phase = (time > t0 && time < t1) ? SimulationPhase::kRigid : SimulationPhase::kElastic;
    t.samples.push_back(s);
  }
  return t;
}

TEST(JumpOutcome, TwistAngleOfRotationsAboutAndOffTheAxis) {
  EXPECT_NEAR(twist_angle(recorded_rotation(0.3), 1), 0.3, 1e-12);
  EXPECT_NEAR(twist_angle(recorded_rotation(-2.0), 1), -2.0, 1e-12);
  EXPECT_NEAR(twist_angle(recorded_rotation(4.0), 1), 4.0 - 2 * M_PI, 1e-12);
  EXPECT_NEAR(twist_angle(recorded_rotation(0.5, Vec3::UnitX()), 1), 0.0, 1e-12);
  // A rotation about y followed by a small tilt about x keeps (nearly) its y twist.
  const Mat3 R = Mat3(Eigen::AngleAxisd(0.05, Vec3::UnitX())) * Mat3(Eigen::AngleAxisd(1.0, Vec3::UnitY()));
  const Eigen::AngleAxisd aa(R);
  EXPECT_NEAR(twist_angle(aa.angle() * aa.axis(), 1), 1.0, 2e-3);
}

TEST(JumpOutcome, FullFlipUnwrapsToTwoPi) {
  const double t0 = 0.01, t1 = 0.21;
  const Trajectory t = ballistic(t0, t1, 2 * M_PI / (t1 - t0));  // exactly one turn in flight
  const std::vector<double> flip = unwrapped_twist(t, 1);
  EXPECT_NEAR(flip.back(), 2 * M_PI, 1e-9);
  for (std::size_t i = 1; i < flip.size(); ++i) ASSERT_LT(std::abs(flip[i] - flip[i - 1]), 0.1);

  JumpMeasureOptions options;
  const JumpOutcome o = measure_jump(t, options);
  EXPECT_TRUE(o.lifted_off);
  EXPECT_TRUE(o.landed);
  EXPECT_NEAR(o.lift_off_time, t0, 1.5e-4);
  EXPECT_NEAR(o.landing_time, t1, 1.5e-4);
  EXPECT_NEAR(o.flip_at_landing, 2 * M_PI, 1e-9);
  EXPECT_NEAR(o.flip_at_end, 2 * M_PI, 1e-9);
  EXPECT_TRUE(o.upright) << "a full turn ends upright";
  EXPECT_NEAR(o.com_at_landing.x(), 0.02 + 0.4 * (t1 - t0), 1e-3);
  EXPECT_NEAR(o.com_at_landing.z(), 0.005, 1e-3);
  const double apex = 0.005 + 9.81 * (t1 - t0) * (t1 - t0) / 8;
  EXPECT_NEAR(o.com_highest.z(), apex, 1e-6);
  EXPECT_NEAR(o.com_highest.x(), 0.02 + 0.4 * (t1 - t0) / 2, 1e-4);
}

TEST(JumpOutcome, BackwardHalfFlipIsNegativeAndNotUpright) {
  const Trajectory t = ballistic(0.01, 0.11, -M_PI / 0.1);
  const JumpOutcome o = measure_jump(t, {});
  EXPECT_NEAR(o.flip_at_landing, -M_PI, 1e-9);
  EXPECT_FALSE(o.upright);
}

TEST(JumpOutcome, ContactFlickerIsNotTheJump) {
  Trajectory t = ballistic(0.05, 0.15, 1.0);
  // Two steps without contact at 20 ms: shorter than min_flight.
  for (TrajectorySample& s : t.samples)
    if (s.time > 0.02 && s.time < 0.0202) s.active_contacts = 0;
  const JumpOutcome o = measure_jump(t, {});
  EXPECT_NEAR(o.lift_off_time, 0.05, 1.5e-4);
  EXPECT_NEAR(o.landing_time, 0.15, 1.5e-4);
}

TEST(JumpOutcome, NoJumpOrNoLandingFallsBackToTheEnd) {
  Trajectory grounded = ballistic(1.0, 2.0, 0.0, 1e-4, 0.05);  // never leaves the ground
  JumpOutcome o = measure_jump(grounded, {});
  EXPECT_FALSE(o.lifted_off);
  EXPECT_FALSE(o.landed);
  EXPECT_DOUBLE_EQ(o.landing_time, grounded.samples.back().time);

  Trajectory flying = ballistic(0.01, 5.0, 1.0, 1e-4, 0.05);  // still airborne at the end
  o = measure_jump(flying, {});
  EXPECT_TRUE(o.lifted_off);
  EXPECT_FALSE(o.landed);
  EXPECT_NEAR(o.flip_at_landing, o.flip_at_end, 1e-15);
  EXPECT_NEAR(o.flip_at_end, 0.04, 1e-3);
}

TEST(JumpOutcome, HeightWhereTheCentreOfMassCrossesAWall) {
  const Trajectory t = ballistic(0.01, 0.21, 0.0);
  double z = 0;
  ASSERT_TRUE(com_height_at_x(t, 0.06, z));  // half way: the apex
  EXPECT_NEAR(z, 0.005 + 9.81 * 0.2 * 0.2 / 8, 1e-6);
  EXPECT_FALSE(com_height_at_x(t, 0.5, z));
}

TEST(JumpOutcome, BadInput) {
  EXPECT_THROW(measure_jump(Trajectory{}, {}), InputError);
  JumpMeasureOptions bad;
  bad.flip_axis = 3;
  EXPECT_THROW(measure_jump(ballistic(0.01, 0.02, 0.0), bad), InputError);
}

}  // namespace
}  // namespace msfab
