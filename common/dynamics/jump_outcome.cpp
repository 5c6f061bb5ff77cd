#include "dynamics/jump_outcome.hpp"

#include <cmath>

#include "core/errors.hpp"

namespace msfab {

double twist_angle(const Vec3& rotation_vector, int axis) {
  const double angle = rotation_vector.norm();
  if (angle == 0) return 0;
  // Quaternion (w, v) of the rotation; its twist about unit axis e is
  // (w, (v.e) e), of angle 2 atan2(v.e, w).
  const double w = std::cos(0.5 * angle);
  const double ve = std::sin(0.5 * angle) * rotation_vector(axis) / angle;
  double twist = 2 * std::atan2(ve, w);
  if (twist > M_PI) twist -= 2 * M_PI;
  if (twist <= -M_PI) twist += 2 * M_PI;
  return twist;
}

std::vector<double> unwrapped_twist(const Trajectory& t, int axis) {
  std::vector<double> out;
  out.reserve(t.samples.size());
  double offset = 0;
  for (const TrajectorySample& s : t.samples) {
    const double raw = twist_angle(s.rotation, axis);
    if (!out.empty()) {
      const double previous = out.back() - offset;
      if (raw - previous > M_PI) offset -= 2 * M_PI;
      if (raw - previous < -M_PI) offset += 2 * M_PI;
    }
    out.push_back(raw + offset);
  }
  return out;
}

JumpOutcome measure_jump(const Trajectory& t, const JumpMeasureOptions& options) {
  if (t.samples.empty()) throw InputError("trajectory '" + t.scene + "': no samples to measure a jump on");
  if (options.flip_axis < 0 || options.flip_axis > 2) throw InputError("jump measure: flip axis must be 0, 1 or 2");
  const std::vector<double> flip = unwrapped_twist(t, options.flip_axis);
  const std::size_t n = t.samples.size(), last = n - 1;

  // First sample after the preload; the quasistatic samples are the pressed state.
  std::size_t first = 0;
  while (first < last && t.samples[first].phase == SimulationPhase::kQuasistatic) ++first;

  JumpOutcome o;
  o.end_time = t.samples[last].time;
  std::size_t lift = n, land = n;
  for (std::size_t i = first; i < n && lift == n; ++i) {
    if (t.samples[i].active_contacts > 0) continue;
    std::size_t j = i;
    while (j < n && t.samples[j].active_contacts == 0) ++j;
    const double flight_end = j < n ? t.samples[j].time : t.samples[last].time;
    if (flight_end - t.samples[i].time >= options.min_flight) {
      lift = i;
      land = j;
    }
    i = j;
  }
  o.lifted_off = lift < n;
  o.landed = land < n;
  const std::size_t at_landing = o.landed ? land : last;
  o.lift_off_time = o.lifted_off ? t.samples[lift].time : o.end_time;
  o.landing_time = t.samples[at_landing].time;
  o.flip_at_landing = flip[at_landing];
  o.flip_at_end = flip[last];
  o.com_at_landing = t.samples[at_landing].center_of_mass;
  o.com_at_end = t.samples[last].center_of_mass;
  o.com_highest = t.samples[first].center_of_mass;
  for (std::size_t i = first; i < n; ++i)
    if (t.samples[i].center_of_mass.z() > o.com_highest.z()) o.com_highest = t.samples[i].center_of_mass;

  const Vec3& r = t.samples[last].rotation;
  const Mat3 R = r.norm() > 0 ? Mat3(Eigen::AngleAxisd(r.norm(), r.normalized())) : Mat3::Identity();
  o.upright = R(2, 2) >= std::cos(options.upright_tolerance);
  return o;
}

bool com_height_at_x(const Trajectory& t, double x, double& height) {
  for (std::size_t i = 1; i < t.samples.size(); ++i) {
    const Vec3& a = t.samples[i - 1].center_of_mass;
    const Vec3& b = t.samples[i].center_of_mass;
    if (a.x() < x && b.x() >= x) {
      const double s = (x - a.x()) / (b.x() - a.x());
      height = a.z() + s * (b.z() - a.z());
      return true;
    }
  }
  return false;
}

}  // namespace msfab
