#pragma once
// One evaluation of the design loop: the scene with the design parameters
// substituted (meshed at the initial design, morphed to these values), run
// through quasistatic press, Newmark dynamics with BBI and rigid flight,
// measured, and turned into the task's objective and constraints.
#include <string>
#include <vector>

#include "design_config.hpp"
#include "dynamics/jump_outcome.hpp"
#include "dynamics/obstacles.hpp"
#include "dynamics/trajectory.hpp"

namespace msfab {

// One run of a design at a factor of the modulus (measure.modulus_scales).
struct ScaledRun {
  double modulus_scale = 1;         // relative to the evaluation's own modulus
  bool ok = false;                  // the simulation succeeded
  double objective = 0;             // this run alone
  std::vector<double> constraints;  // this run alone
  JumpOutcome outcome;
  bool crossed_wall = false;
  double z_over_wall = 0;
};

struct Evaluation {
  int start = 0, index = 0;         // which optimizer start, which of its evaluations
  std::vector<double> parameters;   // physical values, in DesignProblem order
  bool ok = false;                  // false: the simulation failed (penalty values below)
  double objective = 0;             // rad^2 (flip, upright) or m (target)
  std::vector<double> constraints;  // m, feasible when <= 0
  double seconds = 0;               // wall time of the simulation
  JumpOutcome outcome;              // at the scene's time step
  // With measure.confirm_time_step: the run at that step, whose objective
  // and constraints are folded into the ones above (the worse of the two).
  bool confirmed = false;
  double confirm_objective = 0;
  JumpOutcome confirm_outcome;
  bool crossed_wall = false;  // jump-over: the centre of mass crossed the obstacle's middle
  double z_over_wall = 0;     // its height there (m); the wall's foot if it never crossed
  bool confirm_crossed_wall = false;
  double confirm_z_over_wall = 0;
  // With measure.modulus_scales: the run at each factor, folded into the
  // objective and constraints above in the same way (the worst counts).
  // Empty where the run at the scene's modulus failed, and for print
  // variation samples, which are a variation of the modulus themselves.
  std::vector<ScaledRun> scaled;
  int elements = 0;

  // Constraints met to within `tolerance` (m) and the simulation succeeded.
  bool feasible(double tolerance = 1e-6) const;
  double violation() const;  // sum of positive constraint values (m)
  // Every run it was scored by (scene's step, confirmation, each modulus
  // factor) landed.
  bool landed_in_every_run() const;
};

// Fixed-size rows of doubles for the MPI fan-out (layout in the .cpp).
int evaluation_record_size(const DesignProblem& problem);
void pack_evaluation(const DesignProblem& problem, const Evaluation& e, double* row);
Evaluation unpack_evaluation(const DesignProblem& problem, const double* row);

class DesignEvaluator {
 public:
  // Builds and checks the scene at the initial design (InputError on a bad
  // scene, an unknown or unsuitable obstacle).
  explicit DesignEvaluator(const DesignProblem& problem);

  // Safe to call from several threads at once (each call reads its own
  // copy of the scene). A simulation that fails gives ok = false and
  // penalty values; bad input still throws. `modulus_scale` multiplies
  // every material's modulus (print variation); `with_modulus_scales`
  // false skips the runs at measure.modulus_scales.
  Evaluation evaluate(const std::vector<double>& parameters, int start, int index, double modulus_scale = 1.0,
                      bool with_modulus_scales = true) const;

  // The whole run of a design, with the scene's output frames, up to
  // `until` seconds (or the scene's duration if that is shorter): the
  // record pictures of the jump are drawn from. Not stopped by the observer.
  Trajectory run_trajectory(const std::vector<double>& parameters, double until) const;

  int elements() const { return elements_; }
  // Peak memory of one evaluation at the initial design (dynamics_peak_bytes).
  double peak_bytes() const { return peak_bytes_; }
  const Obstacle* obstacle() const { return has_obstacle_ ? &obstacle_ : nullptr; }

 private:
  // One simulation at `time_step` (0: the scene's), measured and scored.
  Evaluation simulate(const std::vector<double>& parameters, double modulus_scale, double time_step) const;

  const DesignProblem& problem_;
  Obstacle obstacle_;
  bool has_obstacle_ = false;
  int elements_ = 0;
  double peak_bytes_ = 0;
};

// The penalty a failed simulation gets: far worse than any outcome, finite
// so that COBYLA's linear models stay usable.
constexpr double kFailedObjective = 100.0;
constexpr double kFailedConstraint = 0.1;  // m

}  // namespace msfab
