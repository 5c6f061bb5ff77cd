#pragma once
// The printed summary of a design run: initial against final design, side
// by side, with the evaluation count and wall time.
#include "design_artifact.hpp"

namespace msfab {

void print_design_summary(const DesignProblem& problem, const DesignRun& run, const std::string& out);

}  // namespace msfab
