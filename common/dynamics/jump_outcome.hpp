#pragma once
// What a jump did, measured on a Trajectory's per-step samples: when the
// body left the ground and landed again, how far it had flipped then and at
// the end, where its centre of mass was, how high it rose, how high it was
// when it passed a wall, and whether it ended upright. These are the
// quantities the objectives and constraints of thesis Fig. 4-17 are made of
// (docs/design_loop.md).
#include <vector>

#include "dynamics/trajectory.hpp"

namespace msfab {

struct JumpMeasureOptions {
  int flip_axis = 1;  // 0 = x, 1 = y, 2 = z
  // An airborne stretch (no active contact) shorter than this does not count
  // as the jump: contact flickers while the body pushes off.
  double min_flight = 0.005;  // s
  // Upright: the body's up axis (rest +z) within this angle of world +z.
  double upright_tolerance = 30.0 * 3.14159265358979323846 / 180.0;  // rad
};

struct JumpOutcome {
  bool lifted_off = false;  // an airborne stretch of at least min_flight
  bool landed = false;      // a contact after it
  bool upright = false;     // at the end
  // Times (s); without a lift-off / landing they are the end time, so that
  // the quantities below always exist ("at landing" is then "at the end").
  double lift_off_time = 0, landing_time = 0;
  // Rotation about the flip axis (rad, right-handed, unwrapped over time:
  // one full flip is 2 pi).
  double flip_at_landing = 0, flip_at_end = 0;
  Vec3 com_at_landing = Vec3::Zero(), com_at_end = Vec3::Zero();
  Vec3 com_highest = Vec3::Zero();  // the sample of greatest centre-of-mass height
  double end_time = 0;
};

// The rotation angle about `axis` of the rotation given as a rotation vector,
// in (-pi, pi]: the angle of the rotation's projection onto that axis
// (swing-twist), so a pure rotation about the axis gives its angle.
double twist_angle(const Vec3& rotation_vector, int axis);

// twist_angle of every sample, unwrapped so that consecutive values differ by
// less than pi (the rotation vector wraps at pi; the samples are one step
// apart, far less than half a turn).
std::vector<double> unwrapped_twist(const Trajectory& trajectory, int axis);

// Measures a trajectory with at least one sample (InputError otherwise).
// Samples of the quasistatic phase are skipped.
JumpOutcome measure_jump(const Trajectory& trajectory, const JumpMeasureOptions& options);

// Height of the centre of mass where it first crosses the vertical plane
// x = `x` moving in +x (linear between samples), or false if it never does.
bool com_height_at_x(const Trajectory& trajectory, double x, double& height);

}  // namespace msfab
