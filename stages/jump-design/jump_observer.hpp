#pragma once
// Watches a dynamics run step by step and stops it once the jump is over:
// a design evaluation needs the flight and the landing, not the seconds of
// resting contact after it, which cost the most per step (many active
// contacts). The observer records its own samples (centre of mass and
// best-fit rotation, exactly as the run's recorder computes them, and the
// nodes touching an obstacle) because a stopped run returns no Trajectory.
#include <memory>
#include <string>
#include <vector>

#include "dynamics/dynamics_scene.hpp"
#include "dynamics/jump_outcome.hpp"
#include "dynamics/rigid_body.hpp"

namespace msfab {

struct ObserverOptions {
  double min_flight = 0.005;  // s: as JumpMeasureOptions::min_flight
  double settle = 0.01;       // s: keep simulating this long after the landing
  // A node touches an obstacle when closer than this fraction of the voxel edge.
  double touch = 0.01;
  // The body whose jump is measured (a catapult's projectile); empty: the
  // whole mesh.
  std::string body;
};

// Thrown from the step callback to end the run early.
struct JumpOver {};

class JumpObserver {
 public:
  JumpObserver(const DynamicsScene& scene, const ObserverOptions& options);
  // The step callback: records a sample; throws JumpOver once `settle`
  // seconds have passed after the landing.
  void on_step(double time, const VecX& positions);
  // The samples so far as a Trajectory (time, centre of mass, rotation,
  // contacts) for measure_jump.
  const Trajectory& trajectory() const { return trajectory_; }

 private:
  const DynamicsScene& scene_;
  ObserverOptions options_;
  std::vector<int> nodes_;  // the measured body's nodes
  RigidBody body_;
  Mat3 R0_;
  double tolerance_ = 0;
  Trajectory trajectory_;
  double airborne_since_ = -1;  // start of the current airborne stretch; -1 while touching
  double landed_at_ = -1;
};

}  // namespace msfab
