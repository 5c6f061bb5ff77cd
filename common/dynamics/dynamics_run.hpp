#pragma once
// One run of a dynamics scene, phase by phase (thesis §4.5.2):
//   preload   a static pluck (clamped body under a load) or a quasistatic
//             press against the obstacles with no-slip contact (B.3)
//   release   the preloaded state starts the Newmark FE dynamics at rest
//   flight    with rigid flight enabled, the body is projected to a rigid
//             body (B.22) once its elastic energy has damped out and no
//             contact is near, stepped with DMV, and projected back (B.23)
//             before the next contact
// and the record of it all as a Trajectory.
#include <functional>

#include "dynamics/dynamics_scene.hpp"
#include "dynamics/trajectory.hpp"

namespace msfab {

struct RunCallbacks {
  // Called after every step with the simulated time reached and the node
  // positions then (3N, node-major).
  std::function<void(double time, const VecX& positions)> on_step;
};

Trajectory run_dynamics_scene(const DynamicsScene& scene, const RunCallbacks& callbacks = {});

}  // namespace msfab
