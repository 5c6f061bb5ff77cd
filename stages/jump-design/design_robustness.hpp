#pragma once
// The final design simulated again under print variation (thesis §4.5:
// more than 85% of the printed designs succeeded). Sample i scales every
// material's modulus by 1 + modulus (2 u - 1) and moves every design
// parameter by geometry (2 u - 1), u uniform in [0, 1) from the run's seed,
// drawn alike on every rank; the samples fan out over ranks and threads like
// the starts, so the result does not depend on either count. With
// checkpoints (control.checkpoint_out) each sample is recorded once
// simulated, and with control.resume a recorded sample is read back instead
// of simulated again; control.max_new_evaluations > 0 simulates at most that
// many new samples (the first ones not recorded) and stops.
#include <cstdint>
#include <vector>

#include "design_config.hpp"
#include "design_evaluation.hpp"
#include "design_search.hpp"

namespace msfab {

struct RobustnessSample {
  double modulus_scale = 1.0;
  Evaluation evaluation;  // at the perturbed parameters
  bool success = false;
};

struct RobustnessResult {
  std::vector<RobustnessSample> samples;
  int successes = 0;
  // Stopped by control.max_new_evaluations before every sample was
  // simulated: the samples are in their checkpoints, not here.
  bool stopped = false;
  double fraction() const { return samples.empty() ? 0.0 : double(successes) / double(samples.size()); }
};

// The task's goal met: flip — landed with the turn within the upright
// tolerance of the target; jump-onto / jump-over — constraints met and
// landed upright (turn within the tolerance of the target, modulo full
// turns); target — landed within robustness.target_distance of target_x.
bool design_succeeded(const DesignProblem& problem, const Evaluation& e);

RobustnessResult check_robustness(const DesignProblem& problem, const DesignEvaluator& evaluator,
                                  const std::vector<double>& design, std::uint64_t seed,
                                  const SearchControl& control = {});

}  // namespace msfab
