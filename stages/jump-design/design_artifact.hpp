#pragma once
// The `msfab.jump_design` artifact (docs/artifacts.md): every evaluation of
// the design loop, the initial and final designs with their outcomes, and
// the final design's print-variation samples.
#include <cstdint>
#include <string>
#include <vector>

#include "design_config.hpp"
#include "design_evaluation.hpp"
#include "design_robustness.hpp"

namespace msfab {

struct DesignRun {
  std::vector<Evaluation> evaluations;  // by start, then index
  std::size_t initial = 0, final = 0;   // indices into evaluations
  RobustnessResult robustness;          // empty without robustness.samples
  double wall_seconds = 0;
  int ranks = 1, threads = 1;
};

// Written to "<path>.tmp" and renamed.
void write_jump_design_artifact(const std::string& path, const DesignProblem& problem, const DesignRun& run,
                                const std::string& config_text, std::uint64_t seed);

// Names of the columns of /evaluations/outcome, in order.
std::vector<std::string> outcome_columns();

}  // namespace msfab
