// msfab-gamut-sample: the material-property gamut of microstructures of two
// phases (two materials, or one and void) or three (two and void; thesis
// §3.2, Fig. 3-15), MPI-parallel.
//
//   1. read the material space, base materials and sampler settings
//   2. cycle 0: the solid cell and random beam cuts of it, homogenized;
//      the gamut level set; the particle population by systematic
//      resampling (or continue from the checkpoint with --resume)
//   3. each cycle:
//        discrete step    every particle changed by random beams, made
//                         symmetric and cleaned; new structures homogenized
//        level set        Zhu-Bridson + fast marching + smoothing (§3.2.3)
//        continuous step  structures nearest the boundary pushed along the
//                         normal, q = p + step grad Phi, by SIMP + MMA
//        level set, coverage, resampling by Eq. 3.1-3.2, checkpoint
//   4. write `msfab.microstructures` and `msfab.gamut`
//
// Homogenizations and continuous optimizations are spread over MPI ranks;
// every random draw is keyed by (seed, cycle, item), so the result is the
// same for any rank or thread count and after --resume.
#include <omp.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "cli/progress.hpp"
#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "homog/elastic_tensor.hpp"
#include "homog/periodic_homogenization.hpp"
#include "io/atomic_file.hpp"
#include "io/commit_group.hpp"
#include "io/path_names.hpp"
#include "parallel/fan_out.hpp"
#include "parallel/mpi_session.hpp"
#include "sampler.hpp"
#include "sampler_checkpoint.hpp"

using namespace msfab;

namespace {

// A base material as a tensor of the space: 6 x 6 in 3D, the plane-strain
// in-plane block in 2D (what a solid cell of it homogenizes to).
MatX base_tensor(const BaseMaterial& m, bool three_d) {
  const Mat6 C = isotropic_tensor(m.E, m.nu);
  return three_d ? MatX(C) : MatX(plane_block(C));
}

void log_step(const char* name, const StepReport& r) {
  spdlog::info("  {}: {} tried, {} added ({} duplicates, {} outside the space, {} thinner than min_feature, {} failed)",
               name, r.tried, r.added, r.duplicates, r.outside, r.thin, r.failed);
}

// A structure set and the gamut sampled from it, as two members of one
// commit; the gamut records the set by the hash of its content. Returns the
// set as an input for later members.
ArtifactInput add_set_and_gamut(CommitGroup& group, const std::string& set_path, const MicrostructureSet& set,
                                const std::string& gamut_path, const Gamut& gamut,
                                std::vector<ArtifactInput> set_inputs, const std::string& run_text,
                                std::uint64_t seed) {
  ArtifactWriter& set_out = group.add(set_path, kMicrostructuresSchema, kMicrostructuresSchemaVersion,
                                      "msfab-gamut-sample", run_text, std::move(set_inputs), seed);
  write_microstructure_set(set_out.file(), "/", set);
  const ArtifactInput set_input = group.as_input(set_out);
  ArtifactWriter& gamut_out =
      group.add(gamut_path, kGamutSchema, kGamutSchemaVersion, "msfab-gamut-sample", run_text, {set_input}, seed);
  write_gamut(gamut_out.file(), gamut);
  return set_input;
}

}  // namespace

int main(int argc, char** argv) {
  const MpiSession mpi(&argc, &argv);
  const int rank = mpi.rank(), size = mpi.size();
  StageApp app("msfab-gamut-sample", "Microstructure gamut sampling, discrete + continuous (thesis 3.2), MPI-parallel");
  app.set_rank(rank);
  app.add_common_options();
  app.set_default_config(kDefaultSamplerConfig);
  bool resume = false;
  int max_cycles = 0;
  std::string structures_path;
  app.flag("--resume", resume, "continue from <out>.checkpoint.h5 (same config and seed required)");
  app.option("--max-cycles", max_cycles,
             "stop after this many cycles in this run, keeping the checkpoint (batch jobs); 0 = all")
      .non_negative();
  app.option("--structures", structures_path,
             "the microstructures artifact (default: <out without .gamut.h5>.microstructures.h5)");
  const int code = app.run(argc, argv, [&](StageContext& ctx) {
    const std::string& out = ctx.require_out();
    const auto t_start = std::chrono::steady_clock::now();

    // 1. Settings.
    const SamplerOptions options = read_sampler_options(ctx.config);
    ctx.finish_config();
    ctx.check_out_folder();
    {
      // What must fit at once: the population, its children and their copies
      // in the set (4 bytes per voxel each), and one cell problem per thread
      // (docs/cli.md, "Memory").
      const bool three_d = options.kind == MaterialSpaceKind::cubic3d;
      const int n = options.resolution;
      const double voxels = std::pow(double(n), three_d ? 3 : 2);
      const double at_once =
          3.0 * (double(options.population) + options.continuous_per_cycle + options.directed_per_cycle);
      const double bytes =
          at_once * voxels * 4 + omp_get_max_threads() * homogenization_peak_bytes(n, n, three_d ? n : 1, "auto");
      ctx.check_memory(bytes,
                       "a population of " + std::to_string(options.population) + " structures of " +
                           std::to_string(options.resolution) + (three_d ? "^3" : "^2") + " voxels",
                       "lower population or resolution");
    }
    if (structures_path.empty()) structures_path = without_suffix(out, {".gamut.h5"}) + ".microstructures.h5";
    // The second artifact is checked before any work, on every rank (a rank
    // that threw alone would leave the others waiting).
    try {
      AtomicFile probe(structures_path);
    } catch (const InputError& e) {
      throw InputError(std::string("--structures ") + e.what());
    }
    const std::string run_text = checkpoint_run_text(ctx.config.resolved_text(), ctx.options.seed);
    const GamutSampler sampler(options, ctx.options.seed);
    if (rank == 0)
      spdlog::info("{} gamut, {}^{} voxel cells, population {}, {} cycles; {} rank(s) x {} thread(s)", options.space,
                   options.resolution, options.kind == MaterialSpaceKind::cubic3d ? 3 : 2, options.population,
                   options.cycles, size, omp_get_max_threads());

    // 2. Initial population, or the checkpoint.
    const std::string ckpt = checkpoint_path(out);
    SamplerState state;
    std::optional<GamutLevelSet> gamut;  // of the current set (none yet after resuming)
    if (resume && std::filesystem::exists(ckpt)) {
      state = read_sampler_checkpoint(ckpt, run_text);
      if (rank == 0)
        spdlog::info("resuming after cycle {} with {} structures", state.cycles_done, state.set.items.size());
    } else {
      if (resume && rank == 0) spdlog::warn("--resume: no checkpoint {} yet, starting from the beginning", ckpt);
      const auto t0 = std::chrono::steady_clock::now();
      StepReport init;
      state = sampler.initialize(&init);
      if (rank == 0) log_step("initial", init);
      gamut = sampler.level_set(state);
      state.history.push_back({0, static_cast<int>(state.set.items.size()), init.added, 0, coverage(*gamut),
                               std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()});
      if (rank == 0) write_sampler_checkpoint(ckpt, run_text, state);
    }

    // 3. Cycles.
    int this_run = 0;
    for (int cycle = state.cycles_done + 1; cycle <= options.cycles; ++cycle) {
      // Checked from the history, so a resumed run stops where the whole run would.
      if (coverage_converged(state.history, options.stop_coverage_growth, options.stop_window)) break;
      if (max_cycles > 0 && this_run == max_cycles) {
        if (rank == 0)
          std::printf("msfab-gamut-sample: stopped after cycle %d of %d (%zu structures); continue with --resume\n",
                      state.cycles_done, options.cycles, state.set.items.size());
        return;
      }
      const auto t0 = std::chrono::steady_clock::now();
      const StepReport discrete = sampler.discrete_step(state, cycle);
      const StepReport continuous = sampler.continuous_step(state, sampler.level_set(state), cycle);
      const StepReport directed = sampler.directed_step(state, cycle);
      gamut = sampler.level_set(state);
      sampler.resample(state, *gamut, cycle);
      state.cycles_done = cycle;
      state.history.push_back({cycle, static_cast<int>(state.set.items.size()), discrete.added,
                               continuous.added + directed.added, coverage(*gamut),
                               std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()});
      if (rank == 0) {
        const GamutCycle& h = state.history.back();
        spdlog::info("cycle {}/{}: {} structures, coverage {:.4f}, {:.1f} s", cycle, options.cycles, h.samples,
                     h.coverage, h.seconds);
        log_step("discrete", discrete);
        log_step("continuous", continuous);
        if (continuous.tried > 0)
          spdlog::info("  continuous: step {:.3f}, {} of {} pushes expanded the gamut", continuous.step,
                       continuous.expanded, continuous.tried);
        if (options.directed_per_cycle > 0) log_step("directed", directed);
        write_sampler_checkpoint(ckpt, run_text, state);
      }
      ++this_run;
    }

    // 4. Artifacts (void variants, a collective step, first).
    StepReport void_report;
    SamplerState voids;
    if (options.void_variants) voids = sampler.void_variants(state, &void_report);
    if (rank == 0) {
      Gamut g;
      g.space = options.space;
      g.property_names = sampler.space().names();
      g.E_stiff = sampler.space().E_stiff();
      g.decades = options.decades;
      g.level_set = gamut ? *gamut : sampler.level_set(state);  // resampling leaves the set as it was
      g.history = state.history;
      const bool three_d = sampler.space().kind() == MaterialSpaceKind::cubic3d;
      g.bound_stiff = base_tensor(options.stiff, three_d);
      g.bound_soft = options.soft_is_void ? MatX::Zero(g.bound_stiff.rows(), g.bound_stiff.cols())
                                          : base_tensor(options.soft, three_d);
      // The structures and the gamut (and their void variants) are one
      // commit: a run killed while writing them leaves the old ones or the
      // new ones, never a new set beside an old gamut.
      CommitGroup artifacts;
      const ArtifactInput set_input =
          add_set_and_gamut(artifacts, structures_path, state.set, out, g, {}, run_text, ctx.options.seed);
      if (options.void_variants) {
        log_step("void variants", void_report);
        if (voids.set.items.empty())
          throw NumericalError("void variants: no structure survives removing the soft material");
        Gamut vg = g;
        vg.level_set = sampler.level_set(voids);
        vg.history.clear();
        vg.bound_soft.setZero();
        const std::string vstem = without_suffix(out, {".gamut.h5"}) + ".void";
        add_set_and_gamut(artifacts, vstem + ".microstructures.h5", voids.set, vstem + ".gamut.h5", vg, {set_input},
                          run_text, ctx.options.seed);
        std::printf("  void variants: %zu of %zu structures -> %s.{gamut,microstructures}.h5\n", voids.set.items.size(),
                    state.set.items.size(), vstem.c_str());
      }
      artifacts.commit();
      std::filesystem::remove(ckpt);
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
      int by_step[5] = {0, 0, 0, 0, 0};
      for (const Microstructure& m : state.set.items) ++by_step[static_cast<int>(m.step)];
      std::printf(
          "msfab-gamut-sample: %s, %zu structures (%d initial, %d discrete, %d continuous, %d directed) after %d "
          "cycles\n",
          options.space.c_str(), state.set.items.size(), by_step[0], by_step[1], by_step[2], by_step[4],
          state.cycles_done);
      std::printf("  coverage %.4f (cycle 0: %.4f)\n", state.history.back().coverage, state.history.front().coverage);
      if (options.three_phase) {
        // How many structures hold void, the soft material, and both: the
        // three-phase gamut is only that where structures mix all three.
        int with_void = 0, with_soft = 0, with_both = 0;
        for (const Microstructure& m : state.set.items) {
          const bool v = std::find(m.ids.begin(), m.ids.end(), 0) != m.ids.end();
          const bool s = std::find(m.ids.begin(), m.ids.end(), 2) != m.ids.end();
          with_void += v, with_soft += s, with_both += v && s;
        }
        std::printf("  phases: %d structures with void, %d with the soft material, %d with both\n", with_void,
                    with_soft, with_both);
      }
      if (options.stop_coverage_growth > 0) {
        const std::size_t w = std::min<std::size_t>(options.stop_window, state.history.size() - 1);
        const double growth = best_coverage_growth(state.history, options.stop_window);
        std::printf("  %s: best coverage grew %.2f%% over the last %zu cycle(s) (stop.coverage_growth %.2f%%)\n",
                    coverage_converged(state.history, options.stop_coverage_growth, options.stop_window)
                        ? "converged"
                        : "not converged, stopped at the cycle limit",
                    100 * growth, w, 100 * options.stop_coverage_growth);
      }
      const std::vector<std::string> names = sampler.space().names();
      for (std::size_t a = 0; a < names.size(); ++a) {
        double lo = HUGE_VAL, hi = -HUGE_VAL;
        for (const Microstructure& m : state.set.items)
          lo = std::min(lo, m.properties[a]), hi = std::max(hi, m.properties[a]);
        std::printf("  range %s: [%.6g, %.6g]\n", names[a].c_str(), lo, hi);
      }
      std::printf("  time: %.1f s wall\n", wall);
      std::printf("  artifacts: %s, %s (`python3 -m msfab report` draws them, docs/python.md)\n", out.c_str(),
                  structures_path.c_str());
    }
  });
  return code;
}
