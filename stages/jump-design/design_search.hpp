#pragma once
// The optimizer of the design loop: COBYLA (NLopt; derivative-free, with
// inequality constraints, since the simulated outcome is not smooth in the
// parameters) on parameters normalized to [0, 1] by their bounds, from the
// initial design and from deterministic perturbations of it. Starts are
// independent, so they fan out over MPI ranks (start i on rank i mod size)
// and the threads of a rank; every result is the same for any rank or
// thread count.
#include <string>
#include <vector>

#include "design_config.hpp"
#include "design_evaluation.hpp"

namespace msfab {

// Start 0 is the initial design. Start k > 0 moves every normalized
// parameter by `spread` initial steps, the signs running through the
// corners of the box (k - 1 in binary), clamped to the bounds; or, with
// space-filling starts, is the k-th point of the Halton sequence over the
// box (bases 2, 3, 5, ... per parameter).
std::vector<double> start_point(const DesignProblem& problem, int start);

// Checkpoints and batch-job limits of a search (design_checkpoint.hpp).
struct SearchControl {
  std::string checkpoint_out;   // the artifact's path; empty: no checkpoints
  std::string run_text;         // config and seed the checkpoints are tagged with
  bool resume = false;          // run_all_starts replays each start's checkpoint first
  int max_new_evaluations = 0;  // per start in this run (0: no limit); then stop, keeping the checkpoints
};

struct StartResult {
  std::vector<Evaluation> evaluations;  // in order, replayed ones included
  bool stopped = false;                 // stopped by max_new_evaluations, not by COBYLA
};

// One COBYLA run of at most max_evaluations simulations; every evaluation
// is logged as it finishes and, with checkpoints, recorded. `replay`: the
// start's recorded evaluations, handed back instead of simulated while
// COBYLA asks for their points.
StartResult run_start(const DesignProblem& problem, const DesignEvaluator& evaluator, int start,
                      const SearchControl& control = {}, std::vector<Evaluation> replay = {});

// Every start on every rank; the evaluations of all starts, ordered by start
// and index, identical on every rank. `stopped`: some start stopped at the
// batch limit (the caller writes no artifact then).
std::vector<Evaluation> run_all_starts(const DesignProblem& problem, const DesignEvaluator& evaluator,
                                       const SearchControl& control = {}, bool* stopped = nullptr);

// The final design: the feasible evaluation of least objective (ties: the
// earlier start, then the earlier evaluation); with none feasible, the one
// of least constraint violation. Index into `evaluations`.
std::size_t best_evaluation(const std::vector<Evaluation>& evaluations);

}  // namespace msfab
