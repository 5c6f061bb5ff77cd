#pragma once
// The design problem of msfab-jump-design (docs/design_loop.md): which
// parameterized scene, which of its parameters vary within which bounds,
// the task (objective and constraints of thesis Fig. 4-17) and the
// optimizer's budget.
#include <string>
#include <vector>

#include "dynamics/jump_outcome.hpp"
#include "io/config.hpp"

namespace msfab {

struct DesignParameter {
  std::string name;
  double lower = 0, upper = 0, step = 0;
  double initial = 0;  // the scene's value: the initial design
  // The value the scene is meshed at and morphed from: the scene's
  // reference_parameters entry if it has one, else the initial design.
  double reference = 0;
};

enum class DesignTask {
  kFlip,      // minimize (theta at landing - target)^2
  kTarget,    // minimize |x_c at landing - x_target|
  kJumpOnto,  // upright at landing s.t. landing beyond the obstacle's near face and above its top
  kJumpOver,  // upright at landing s.t. landing beyond the far face, clearing the top when over it
};
const char* design_task_name(DesignTask task);

// After the search, the final design is simulated again under print
// variation (thesis §4.5: > 85% of printed designs succeeded): every
// material's modulus times a factor uniform in [1 - modulus, 1 + modulus]
// and every design parameter (a length) moved uniformly within
// +-geometry. What counts as success depends on the task
// (design_robustness.hpp).
struct RobustnessCheck {
  int samples = 0;                // 0: no check
  double modulus = 0.2;           // relative
  double geometry = 2e-4;         // m
  double target_distance = 0.01;  // m: a target-task landing within this counts as a hit
};

struct DesignProblem {
  std::string scene_path;
  std::vector<std::string> scene_set;  // --set style overrides of the scene
  std::vector<DesignParameter> parameters;
  DesignTask task = DesignTask::kFlip;
  double target_flip = 0;  // rad: flip wanted at landing (flip and upright objectives)
  double target_x = 0;     // m (target)
  std::string obstacle;    // scene obstacle (jump-onto, jump-over)
  std::string body;        // measured body (measure.body; empty: the whole mesh)
  double clearance = 0;    // m: extra height over the obstacle top the constraints ask for
  JumpMeasureOptions measure;
  double settle = 0.01;  // s: simulated after the landing before the run is stopped
  // s: every evaluation runs again at this time step and scores the worse
  // of the two (measure.confirm_time_step; 0: once, at the scene's step).
  // An outcome decided by a graze or an edge strike changes with the step,
  // so a design whose score holds at both does not rest on one.
  double confirm_time_step = 0;
  // Every evaluation also runs with every material's modulus times each of
  // these factors (at the scene's time step) and scores the worst of all
  // its runs (measure.modulus_scales; empty: the scene's modulus only). A
  // print's modulus varies by tens of percent and the turn in the air
  // follows it (docs/design_loop.md), so a design scored this way does not
  // rest on one modulus.
  std::vector<double> modulus_scales;
  // Optimizer.
  int max_evaluations = 20;  // per start
  int starts = 1;            // the initial design and starts - 1 more (see start_point)
  double spread = 1.0;       // perturbation size in initial steps (starts around the initial design)
  // Where starts 1.. begin: `around_initial` (corners at `spread` steps) or
  // `space_filling` (a Halton sequence over the whole box, independent of
  // the initial design: a global stage).
  bool space_filling_starts = false;
  double xtol = 0.01;          // stop when a step changes no normalized parameter by more
  double stop_below = 0;       // stop a start once its objective is below this (0: never)
  double length_scale = 0.01;  // m: constraints and distances are divided by it for COBYLA
  RobustnessCheck robustness;
  std::string config_source;
};

// Reads the design config and the scene's initial parameter values
// (InputError naming the file, key and problem: unknown parameters, bounds
// in the wrong order, an initial design outside its bounds).
DesignProblem read_design_problem(const Config& config);

// Names of the constraints of a task, in the order they are evaluated.
std::vector<std::string> constraint_names(DesignTask task);

}  // namespace msfab
