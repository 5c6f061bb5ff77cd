#pragma once
// Checkpoints of the design loop, one per optimizer start,
// "<out>.start<k>.checkpoint.h5", and one per print-variation sample,
// "<out>.sample<i>.checkpoint.h5" (io/checkpoint_file.hpp rules: rewritten
// whole after every evaluation, tagged with the config and seed). One file
// per start or sample, because they run at once on different ranks and
// threads and each writes only its own; a run resumed on another number of
// ranks finds every file all the same. COBYLA is deterministic, so a
// resumed start asks for the recorded points again in the same order and
// gets the recorded evaluations back without simulating them; a recorded
// sample is not simulated again.
#include <string>
#include <vector>

#include "design_config.hpp"
#include "design_evaluation.hpp"

namespace msfab {

std::string start_checkpoint_path(const std::string& out, int start);
std::string sample_checkpoint_path(const std::string& out, int sample);

// Thread-safe: writes of concurrent starts and samples are serialized.
void write_evaluations_checkpoint(const std::string& path, const std::string& run_text, const DesignProblem& problem,
                                  const std::vector<Evaluation>& evaluations);

// The recorded evaluations; an empty list when there is no file. Read
// before the starts fan out (not thread-safe). InputError
// naming the file when it is not such a checkpoint or was written by
// another run (config or seed).
std::vector<Evaluation> read_evaluations_checkpoint(const std::string& path, const std::string& run_text,
                                                    const DesignProblem& problem);

}  // namespace msfab
