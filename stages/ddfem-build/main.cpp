// msfab-ddfem-build: the offline DDFEM coarse-material database (thesis
// §2.3).
//
//   1. read the palette (level 1: Neo-Hookean E, nu, density; void is
//      implicit) or the level-1 database that is the palette of level 2
//   2. plan the fits: level 1, the n^8 all-solid block combinations grouped
//      into orbits of the 48 cube symmetries (one representative each);
//      level 2, the hierarchy 2x1x1 -> 1x2x1 -> 1x1x2 of compressed pair
//      databases over the level-1 materials (§2.3.5), whose final
//      representatives are the blocks to fit
//   3. in rounds, fit the blocks (spread over MPI ranks, and over threads
//      within a rank): force-space sampling, anisotropy directions,
//      regularized NNLS of Eq. 2.9; rank 0 checkpoints after each round
//   4. assemble the database (level 1: each orbit's fit mapped to its
//      members) and write `msfab.coarse_db`
//
// A fit depends only on its block and the config, so the database is
// identical for any rank or thread count and after resume.
#include <omp.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "build_options.hpp"
#include "build_plan.hpp"
#include "checkpoint.hpp"
#include "cli/progress.hpp"
#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "fit_record.hpp"
#include "parallel/fan_out.hpp"
#include "parallel/mpi_session.hpp"

using namespace msfab;

namespace {

// Fits this rank's share of items [begin, end) and gathers all of them on
// every rank (parallel/fan_out.hpp: ranks stay in step; the payload is small).
void fit_round(const BuildPlan& plan, const BuildOptions& options, const std::vector<std::int64_t>& pending,
               std::size_t begin, std::size_t end, FittedOrbits& done) {
  const int count = static_cast<int>(end - begin);
  const int record = static_cast<int>(fit_record_size(plan.points));
  const std::vector<double> all = fan_out(count, record, [&](int i, double* row) {
    const std::int64_t block = pending[begin + i];
    CoarseMaterialFit fit(plan.points);
    const bool element = plan.void_children(block) < 8;  // an all-void block has nothing to fit
    try {
      if (element) fit = fit_coarse_material(plan.block(block), options.fit);
    } catch (const std::exception& e) {  // a failed block is recorded as not fitted (a resume retries it)
      fit = CoarseMaterialFit(plan.points);
      spdlog::error("block {}: {}", block, e.what());
    }
    if (element && !fit.fitted) spdlog::warn("block {}: not fitted: {}", block, fit.not_fitted_reason);
    pack_fit(fit, row);
  });
  for (int i = 0; i < count; ++i)
    done[pending[begin + i]] = unpack_fit(&all[static_cast<std::size_t>(i) * record], plan.points);
}

}  // namespace

int main(int argc, char** argv) {
  const MpiSession mpi(&argc, &argv);
  const int rank = mpi.rank(), size = mpi.size();
  StageApp app("msfab-ddfem-build", "Offline DDFEM coarse-material database (thesis §2.3), MPI-parallel");
  app.set_rank(rank);
  app.add_common_options();
  app.set_default_config(kDefaultBuildConfig);
  bool resume = false;
  int max_rounds = 0;
  app.flag("--resume", resume, "continue from <out>.checkpoint.h5 (same config required)");
  app.option("--max-rounds", max_rounds,
             "stop after this many rounds, keeping the checkpoint (for time-limited batch jobs); 0 = all")
      .non_negative();
  const int code = app.run(argc, argv, [&](StageContext& ctx) {
    const std::string& out = ctx.require_out();
    const auto t0 = std::chrono::steady_clock::now();

    // 1. Palette (or the level-1 database) and options.
    const BuildOptions options = read_build_options(ctx.config);
    ctx.finish_config();
    ctx.check_out_folder();
    {
      // Every block in flight (one per thread) holds its force patterns (4
      // kinds per direction and 12 edge pinches) and their samples at both
      // signs and every magnitude, about 1 kB each with a patch's loads and
      // the fit's rows (docs/cli.md, "Memory").
      const ForceSamplingOptions& f = options.fit.sampling;
      const double patterns = 4.0 * ((f.include_axes ? 3.0 : 0.0) + f.sphere_directions) + 12.0;
      const double bytes = omp_get_max_threads() * patterns * (1.0 + 2.0 * f.magnitudes) * 1024.0;
      ctx.check_memory(bytes,
                       std::to_string(f.sphere_directions) + " sampling directions x " + std::to_string(f.magnitudes) +
                           " magnitudes per block (sampling.sphere_directions, sampling.magnitudes)",
                       "sample fewer directions or magnitudes");
    }

    // 2. What to fit.
    const bool level2 = !options.base_database.empty();
    const MemoryCheck check_memory = [&](double bytes, const std::string& what, const std::string& remedy) {
      ctx.check_memory(bytes, what, remedy);
    };
    const BuildPlan plan = level2 ? plan_level2(options, check_memory) : plan_level1(options);
    const std::string config_text =
        ctx.config.resolved_text() + (plan.fingerprint.empty() ? "" : "# " + plan.fingerprint + "\n");
    if (rank == 0) {
      if (level2)
        spdlog::info(
            "level 2 over {} level-1 materials: {} blocks of 64-point elements to fit; {} rank(s) x {} thread(s)",
            plan.db.level1->entries.size(), plan.items.size(), size, omp_get_max_threads());
      else
        spdlog::info("{} materials: {} combinations in {} orbits{}; {} rank(s) x {} thread(s)", plan.db.num_materials(),
                     plan.db.num_combinations(), plan.items.size(),
                     options.use_symmetry ? " of the cube symmetries" : "", size, omp_get_max_threads());
    }

    // 3. Fit in rounds, with a checkpoint after each.
    const std::string ckpt = checkpoint_path(out);
    FittedOrbits done;
    if (resume && std::filesystem::exists(ckpt)) {
      done = read_checkpoint(ckpt, config_text, plan.points);
      if (rank == 0)
        spdlog::info("resuming: {} of {} blocks already fitted in {}", done.size(), plan.items.size(), ckpt);
    } else if (resume && rank == 0) {
      spdlog::warn("--resume: no checkpoint {} yet, starting from the beginning", ckpt);
    }
    std::vector<std::int64_t> pending;
    for (std::int64_t item : plan.items)  // a resume retries blocks that failed
      if (!done.count(item) || !done.at(item).fitted) pending.push_back(item);
    Progress progress(level2 ? "fitting level-2 blocks" : "fitting orbits", plan.items.size());
    progress.set(plan.items.size() - pending.size());
    int rounds = 0;
    const std::size_t per_round = static_cast<std::size_t>(options.orbits_per_round);
    for (std::size_t begin = 0; begin < pending.size(); begin += per_round) {
      if (max_rounds > 0 && rounds == max_rounds) {
        if (rank == 0)
          std::printf("msfab-ddfem-build: stopped after %d rounds (%zu of %zu blocks fitted); continue with --resume\n",
                      rounds, done.size(), plan.items.size());
        return;
      }
      const std::size_t end = std::min(pending.size(), begin + per_round);
      fit_round(plan, options, pending, begin, end, done);
      if (rank == 0) write_checkpoint(ckpt, config_text, done, plan.points);
      progress.set(plan.items.size() - (pending.size() - end));
      ++rounds;
    }
    progress.done();

    // 4. The database.
    double fit_seconds = 0;
    for (const auto& [item, fit] : done) fit_seconds += fit.seconds;
    const CoarseDatabase db = assemble_database(plan, done);
    if (rank == 0) {
      write_coarse_db(out, db, config_text, ctx.command_line, ctx.options.seed, "msfab-ddfem-build");
      std::filesystem::remove(ckpt);
      double worst = 0, mean = 0;
      for (const auto& [rep, fit] : done) worst = std::max(worst, fit.heldout_error), mean += fit.heldout_error;
      mean /= std::max<std::size_t>(1, done.size());
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (level2)
        std::printf("msfab-ddfem-build: %zu level-2 coarse materials over %zu level-1 materials\n", db.entries.size(),
                    db.level1->entries.size());
      else
        std::printf("msfab-ddfem-build: %lld combinations (%d orbits) of %d materials, level 1\n",
                    static_cast<long long>(db.num_combinations()), db.num_orbits, db.num_materials());
      std::printf(
          "  held-out relative energy error: mean %.4f, worst %.4f\n"
          "    (per block, the RMS of (coarse - fine energy) / fine energy over the force samples kept out of "
          "its fit, fit.heldout_fraction; 0 would be exact, 0.1 is 10%% energy error; docs/ddfem.md)\n",
          mean, worst);
      std::printf("  time: %.2f s wall, %.2f s of fitting (%.2f blocks/s per core)\n", wall, fit_seconds,
                  fit_seconds > 0 ? done.size() / fit_seconds : 0.0);
      std::printf("  artifact: %s (%.1f kB)\n", out.c_str(), std::filesystem::file_size(out) / 1024.0);
    }
  });
  return code;
}
