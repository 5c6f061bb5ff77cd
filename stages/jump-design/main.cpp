// msfab-jump-design: the design loop of thesis §4.5.1. Two (or more)
// geometric parameters of a jumping mechanism are optimized for a dynamic
// goal (Fig. 4-17: flip and land upright, hit a target, jump onto or over
// an obstacle and land upright):
//
//   1. read the design problem and check the parameterized scene at the
//      initial design and at every corner of the parameter bounds
//   2. COBYLA starts (the initial design and perturbations of it) fan out
//      over MPI ranks and threads; each evaluation presses the mechanism
//      quasistatically, releases it into Newmark dynamics with BBI impact
//      and rigid flight, and measures the jump; each start keeps a
//      checkpoint of its evaluations (--resume replays it)
//   3. the final design is the best feasible evaluation of all starts
//   4. with robustness.samples > 0, the final design again under print
//      variation (modulus and geometry), fanned out like the starts: the
//      fraction of samples that still meet the goal; each sample is
//      checkpointed, and --resume does not simulate a recorded one again
//   5. write `msfab.jump_design` (every evaluation, initial and final
//      designs, the variation samples) and print initial against final
//   6. run the final design once more, whole, to its landing and `settle`
//      after it, and write that run as `msfab.trajectory` (frames of the
//      jump for pictures and ParaView)
#include <omp.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "cli/progress.hpp"
#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "design_artifact.hpp"
#include "design_checkpoint.hpp"
#include "design_config.hpp"
#include "design_evaluation.hpp"
#include "design_report.hpp"
#include "design_robustness.hpp"
#include "design_search.hpp"
#include "dynamics/trajectory.hpp"
#include "io/atomic_file.hpp"
#include "io/checkpoint_file.hpp"
#include "io/path_names.hpp"
#include "parallel/fan_out.hpp"
#include "parallel/mpi_session.hpp"

using namespace msfab;

int main(int argc, char** argv) {
  const MpiSession mpi(&argc, &argv);
  const int rank = mpi.rank(), size = mpi.size();
  StageApp app("msfab-jump-design", "Design loop for jumping mechanisms with COBYLA over dynamics runs (thesis 4.5.1)");
  app.set_rank(rank);
  app.add_common_options();
  std::string trajectory_path;
  app.option("--trajectory", trajectory_path,
             "the final design's run (default: <out without .jump_design.h5>.final.trajectory.h5)");
  bool resume = false;
  int max_new_evaluations = 0;
  app.flag("--resume", resume, "continue every start from <out>.start<k>.checkpoint.h5 (same config and seed)");
  app.option("--max-new-evaluations", max_new_evaluations,
             "stop each start, and then the print variation, after this many simulations in this run, keeping "
             "the checkpoints (batch jobs); 0 = no limit");
  const int code = app.run(argc, argv, [&](StageContext& ctx) {
    const std::string& out = ctx.require_out();
    const auto t_start = std::chrono::steady_clock::now();

    // 1. Problem and scene checks.
    const DesignProblem problem = read_design_problem(ctx.config);
    ctx.finish_config();
    const DesignEvaluator evaluator(problem);
    ctx.check_out_folder();
    if (trajectory_path.empty())
      trajectory_path = without_suffix(out, {".jump_design.h5", ".h5"}) + ".final.trajectory.h5";
    try {  // checked before any work, on every rank
      AtomicFile probe(trajectory_path);
    } catch (const InputError& e) {
      throw InputError(std::string("--trajectory ") + e.what());
    }
    ctx.check_memory(omp_get_max_threads() * evaluator.peak_bytes(),
                     "one simulation of " + std::to_string(evaluator.elements()) + " elements per thread (" +
                         std::to_string(omp_get_max_threads()) + " threads)",
                     "use fewer threads (--threads) or a coarser scene");
    if (rank == 0)
      spdlog::info(
          "{} design of {}: {} parameters, {} elements, {} start(s) x <= {} evaluations; {} rank(s) x {} thread(s)",
          design_task_name(problem.task), problem.scene_path, problem.parameters.size(), evaluator.elements(),
          problem.starts, problem.max_evaluations, size, omp_get_max_threads());

    // 2-3. Starts (checkpointed after every evaluation) and the final design.
    if (max_new_evaluations < 0)
      throw InputError("--max-new-evaluations = " + std::to_string(max_new_evaluations) + ": must be >= 0");
    SearchControl control;
    control.checkpoint_out = out;
    control.run_text = checkpoint_run_text(ctx.config.resolved_text(), ctx.options.seed);
    control.resume = resume;
    control.max_new_evaluations = max_new_evaluations;
    DesignRun run;
    bool stopped = false;
    run.evaluations = run_all_starts(problem, evaluator, control, &stopped);
    if (stopped) {
      if (rank == 0)
        std::printf(
            "msfab-jump-design: stopped after %d new evaluations per start (%zu recorded); continue with "
            "--resume\n",
            max_new_evaluations, run.evaluations.size());
      return;
    }
    run.final = best_evaluation(run.evaluations);
    run.initial = 0;  // start 0 begins at the initial design (checked below)
    run.ranks = size;
    run.threads = omp_get_max_threads();
    const Evaluation& first = run.evaluations.front();
    bool at_initial = first.start == 0 && first.index == 0;
    for (std::size_t i = 0; at_initial && i < problem.parameters.size(); ++i)
      at_initial = std::abs(first.parameters[i] - problem.parameters[i].initial) <=
                   1e-12 * (problem.parameters[i].upper - problem.parameters[i].lower);
    if (!at_initial) throw NumericalError("design loop: start 0 did not begin with the initial design");

    // 4. Print variation.
    if (problem.robustness.samples > 0) {
      run.robustness =
          check_robustness(problem, evaluator, run.evaluations[run.final].parameters, ctx.options.seed, control);
      if (run.robustness.stopped) {
        if (rank == 0)
          std::printf("msfab-jump-design: print variation stopped after %d new samples; continue with --resume\n",
                      max_new_evaluations);
        return;
      }
    }
    run.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();

    // 5. Artifact and summary.
    if (rank == 0) {
      write_jump_design_artifact(out, problem, run, ctx.config.resolved_text(), ctx.options.seed);
      print_design_summary(problem, run, out);
      for (int start = 0; start < problem.starts; ++start) std::filesystem::remove(start_checkpoint_path(out, start));
      for (int i = 0; i < problem.robustness.samples; ++i) std::filesystem::remove(sample_checkpoint_path(out, i));
    }

    // 6. The final design's whole run.
    if (rank == 0) {
      const Evaluation& best = run.evaluations[run.final];
      const Trajectory t = evaluator.run_trajectory(best.parameters, best.outcome.landing_time + problem.settle);
      TrajectoryProvenance provenance;
      provenance.executable = "msfab-jump-design";
      provenance.config_text = ctx.config.resolved_text();
      provenance.seed = ctx.options.seed;
      write_trajectory_artifact(trajectory_path, t, provenance);
      spdlog::info("final design's run ({} frames to {:.4f} s): {}", t.frames.size(),
                   t.samples.empty() ? 0.0 : t.samples.back().time, trajectory_path);
    }
  });
  return code;
}
