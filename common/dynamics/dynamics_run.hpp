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

// Peak memory of run_dynamics_scene, from /usr/bin/time on dropped cubes of
// 1 000 to 15 625 elements (docs/cli.md, "Memory"): about 30 kB per element
// for the stiffness, damping, mass and contact matrices and the Newton
// vectors, CHOLMOD's factor (about 1 kB x elements^(4/3)), and the output
// frames the trajectory keeps (positions and velocities every
// output_every steps).
double dynamics_peak_bytes(const DynamicsScene& scene);

}  // namespace msfab
