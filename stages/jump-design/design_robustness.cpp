#include "design_robustness.hpp"

#include <spdlog/spdlog.h>

#include <cmath>
#include <random>

#include "core/errors.hpp"
#include "design_checkpoint.hpp"
#include "parallel/fan_out.hpp"

namespace msfab {

bool design_succeeded(const DesignProblem& p, const Evaluation& e) {
  if (!e.landed_in_every_run()) return false;
  // The objective is the worst of the evaluation's runs (confirmation
  // step, modulus factors; design_evaluation.hpp): miss^2 of the turn, or
  // the target distance.
  const double tolerance = p.measure.upright_tolerance;
  switch (p.task) {
    case DesignTask::kFlip: return e.objective <= tolerance * tolerance;
    case DesignTask::kTarget: return e.objective <= p.robustness.target_distance;
    case DesignTask::kJumpOnto:
    case DesignTask::kJumpOver: return e.feasible() && e.objective <= tolerance * tolerance;
  }
  return false;
}

RobustnessResult check_robustness(const DesignProblem& p, const DesignEvaluator& evaluator,
                                  const std::vector<double>& design, std::uint64_t seed, const SearchControl& control) {
  const RobustnessCheck& r = p.robustness;
  const std::size_t np = design.size();
  // Every rank draws all samples, so sample i is the same wherever it runs.
  std::mt19937_64 rng(seed ^ 0x9e3779b97f4a7c15ULL);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<double> modulus(r.samples);
  std::vector<std::vector<double>> parameters(r.samples, design);
  for (int i = 0; i < r.samples; ++i) {
    modulus[i] = 1.0 + r.modulus * (2 * unit(rng) - 1);
    for (std::size_t j = 0; j < np; ++j) parameters[i][j] += r.geometry * (2 * unit(rng) - 1);
  }
  // Recorded samples, read before the fan-out (a bad checkpoint is bad
  // input, exit 2, not a failure inside the workers).
  const bool checkpoints = !control.checkpoint_out.empty();
  std::vector<std::vector<Evaluation>> recorded(r.samples);
  if (checkpoints && control.resume) {
    int found = 0;
    for (int i = 0; i < r.samples; ++i) {
      const std::string path = sample_checkpoint_path(control.checkpoint_out, i);
      recorded[i] = read_evaluations_checkpoint(path, control.run_text, p);
      if (recorded[i].size() > 1 || (recorded[i].size() == 1 && recorded[i][0].parameters != parameters[i]))
        throw InputError(path + ": the recorded sample is not print-variation sample " + std::to_string(i) +
                         " of this run");
      found += static_cast<int>(recorded[i].size());
    }
    if (found > 0) spdlog::info("print variation: {} of {} samples recorded, not simulated again", found, r.samples);
    // No rank writes a sample's checkpoint before every rank has read them
    // all: the ranks must agree on which samples are recorded.
    mpi_barrier();
  }
  // A batch limit (control.max_new_evaluations) simulates the first samples
  // not yet recorded, by index, so the split does not depend on the ranks.
  std::vector<char> simulate(r.samples, 0);
  int budget = control.max_new_evaluations > 0 ? control.max_new_evaluations : r.samples;
  for (int i = 0; i < r.samples; ++i)
    if (recorded[i].empty() && budget > 0) simulate[i] = 1, --budget;
  RobustnessResult result;
  for (int i = 0; i < r.samples; ++i) result.stopped = result.stopped || (recorded[i].empty() && !simulate[i]);
  const int per = evaluation_record_size(p);
  const std::vector<double> records = fan_out(r.samples, per, [&](int i, double* row) {
    if (!recorded[i].empty()) {
      pack_evaluation(p, recorded[i][0], row);
      return;
    }
    if (!simulate[i]) return;
    const Evaluation e = evaluator.evaluate(parameters[i], -1, i, modulus[i], false);
    spdlog::info("print variation {}: E x {:.3f}, {} : {} ({:.1f} s)", i, modulus[i], fmt::join(parameters[i], ", "),
                 design_succeeded(p, e) ? "succeeds" : "fails", e.seconds);
    pack_evaluation(p, e, row);
    if (checkpoints) {
      const std::string path = sample_checkpoint_path(control.checkpoint_out, i);
      try {
        write_evaluations_checkpoint(path, control.run_text, p, {e});
      } catch (const std::exception& ex) {
        spdlog::warn("print variation {}: checkpoint {} not written ({}); the check goes on", i, path, ex.what());
      }
    }
  });
  if (result.stopped) return result;
  for (int i = 0; i < r.samples; ++i) {
    RobustnessSample s;
    s.modulus_scale = modulus[i];
    s.evaluation = unpack_evaluation(p, records.data() + static_cast<std::size_t>(i) * per);
    s.success = design_succeeded(p, s.evaluation);
    result.successes += s.success;
    result.samples.push_back(std::move(s));
  }
  return result;
}

}  // namespace msfab
