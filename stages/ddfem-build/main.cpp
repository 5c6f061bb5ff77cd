// msfab-ddfem-build: the offline DDFEM coarse-material database (thesis
// §2.3, level 1).
//
//   1. read the palette (Neo-Hookean E, nu, density; void is implicit)
//   2. enumerate the n^8 all-solid block combinations and group them into
//      orbits of the 48 cube symmetries (one representative each)
//   3. in rounds, fit the representatives (spread over MPI ranks, and over
//      threads within a rank): force-space sampling, anisotropy directions,
//      regularized NNLS of Eq. 2.9; rank 0 checkpoints after each round
//   4. map each representative's fit to its orbit and write `msfab.coarse_db`
//
// The fit of a representative depends only on its ids and the config, so
// the database is identical for any rank or thread count and after resume.
#include <mpi.h>
#include <omp.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "build_options.hpp"
#include "checkpoint.hpp"
#include "cli/progress.hpp"
#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "ddfem/cube_symmetry.hpp"
#include "ddfem/fine_block.hpp"
#include "fit_record.hpp"

using namespace msfab;

namespace {

struct Orbits {
  std::vector<std::int64_t> representative_of;  // per combination code
  std::vector<std::int64_t> representatives;    // increasing codes
};

Orbits group_into_orbits(const CoarseDatabase& db, bool use_symmetry) {
  Orbits o;
  const std::int64_t N = db.num_combinations();
  o.representative_of.resize(N);
  for (std::int64_t code = 0; code < N; ++code) {
    const std::int64_t rep = use_symmetry ? db.combination_code(canonical_block(db.combination_ids(code)).ids) : code;
    o.representative_of[code] = rep;
    if (rep == code) o.representatives.push_back(code);
  }
  return o;
}

// Fits this rank's share of orbits [begin, end) and gathers all of them on
// every rank (allgather keeps ranks in step; the payload is small).
void fit_round(const CoarseDatabase& db, const BuildOptions& options, const std::vector<std::int64_t>& todo,
               std::size_t begin, std::size_t end, int rank, int size, FittedOrbits& done) {
  const int count = static_cast<int>(end - begin);
  std::vector<double> mine(static_cast<std::size_t>(count) * kFitRecordSize, 0.0);
  const auto palette = db.palette();
#pragma omp parallel for schedule(dynamic, 1)
  for (int i = 0; i < count; ++i) {
    if (i % size != rank) continue;
    const BlockMaterials ids = db.combination_ids(todo[begin + i]);
    CoarseMaterialFit fit;
    try {
      fit = fit_coarse_material(make_fine_block(ids, palette, options.voxel_size), options.fit);
    } catch (const std::exception& e) {  // must not escape the parallel region
      fit = CoarseMaterialFit();
      fit.material_ids = ids;
      spdlog::error("orbit {}: {}", todo[begin + i], e.what());
    }
    pack_fit(fit, &mine[static_cast<std::size_t>(i) * kFitRecordSize]);
  }
  // Rows not owned are zero, so a sum over ranks assembles the round exactly.
  std::vector<double> all(mine.size());
  MPI_Allreduce(mine.data(), all.data(), static_cast<int>(mine.size()), MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  for (int i = 0; i < count; ++i) done[todo[begin + i]] = unpack_fit(&all[static_cast<std::size_t>(i) * kFitRecordSize]);
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);

  StageApp app("msfab-ddfem-build", "Offline DDFEM coarse-material database (thesis §2.3), MPI-parallel");
  app.add_common_options();
  app.set_default_config(kDefaultBuildConfig);
  bool resume = false;
  int max_rounds = 0;
  app.cli().add_flag("--resume", resume, "continue from <out>.checkpoint.h5 (same config required)");
  app.cli().add_option("--max-rounds", max_rounds,
                       "stop after this many rounds, keeping the checkpoint (for time-limited batch jobs); 0 = all")
      ->check(CLI::NonNegativeNumber);
  const int code = app.run(argc, argv, [&](StageContext& ctx) {
    const std::string& out = ctx.require_out();
    const auto t0 = std::chrono::steady_clock::now();

    if (rank != 0) {  // one voice per job
      Progress::set_quiet(true);
      spdlog::set_level(spdlog::level::warn);
    }

    // 1. Palette and options.
    const BuildOptions options = read_build_options(ctx.config);
    ctx.config.check_no_unknown_keys();
    const std::string config_text = ctx.config.resolved_text();
    if (!std::filesystem::is_directory(std::filesystem::absolute(out).parent_path()))
      throw InputError(out + ": output folder does not exist");
    CoarseDatabase db;
    db.level = 1;
    db.materials = options.materials;

    // 2. Combinations and orbits.
    const Orbits orbits = group_into_orbits(db, options.use_symmetry);
    db.num_orbits = static_cast<int>(orbits.representatives.size());
    if (rank == 0)
      spdlog::info("{} materials: {} combinations in {} orbits{}; {} rank(s) x {} thread(s)", db.num_materials(),
                   db.num_combinations(), db.num_orbits, options.use_symmetry ? " of the cube symmetries" : "",
                   size, omp_get_max_threads());

    // 3. Fit the representatives in rounds, with a checkpoint after each.
    const std::string ckpt = checkpoint_path(out);
    FittedOrbits done;
    if (resume && std::filesystem::exists(ckpt)) {
      done = read_checkpoint(ckpt, config_text);
      if (rank == 0) spdlog::info("resuming: {} of {} orbits already fitted in {}", done.size(), db.num_orbits, ckpt);
    } else if (resume && rank == 0) {
      spdlog::warn("--resume: no checkpoint {} yet, starting from the beginning", ckpt);
    }
    std::vector<std::int64_t> todo;
    for (std::int64_t rep : orbits.representatives)
      if (!done.count(rep)) todo.push_back(rep);
    Progress progress("fitting orbits", orbits.representatives.size());
    progress.set(done.size());
    int rounds = 0;
    const std::size_t per_round = static_cast<std::size_t>(options.orbits_per_round);
    for (std::size_t begin = 0; begin < todo.size(); begin += per_round) {
      if (max_rounds > 0 && rounds == max_rounds) {
        if (rank == 0)
          std::printf("msfab-ddfem-build: stopped after %d rounds (%zu of %d orbits fitted); continue with --resume\n",
                      rounds, done.size(), db.num_orbits);
        return;
      }
      const std::size_t end = std::min(todo.size(), begin + per_round);
      fit_round(db, options, todo, begin, end, rank, size, done);
      if (rank == 0) write_checkpoint(ckpt, config_text, done);
      progress.set(done.size());
      ++rounds;
    }
    progress.done();

    // 4. Every combination from its orbit's representative.
    const auto& symmetries = cube_symmetries();
    db.entries.resize(db.num_combinations());
    db.entry_of.resize(db.num_combinations());
    db.orbit.resize(db.num_combinations());
    double fit_seconds = 0;
    int unfitted = 0;
    for (const auto& [rep, fit] : done) {
      fit_seconds += fit.seconds;
      unfitted += !fit.fitted;
    }
    for (std::int64_t c = 0; c < db.num_combinations(); ++c) {
      const BlockMaterials ids = db.combination_ids(c);
      const std::int64_t rep = orbits.representative_of[c];
      db.orbit[c] = static_cast<int>(rep);
      db.entry_of[c] = static_cast<int>(c);
      const CoarseMaterialFit& image = done.at(rep);
      if (rep == c) {
        db.entries[c] = image;
      } else {
        const CanonicalBlock canon = canonical_block(ids);
        db.entries[c] = map_fit_back(symmetries[canon.symmetry], image, ids);
      }
    }
    if (unfitted > 0) throw NumericalError(std::to_string(unfitted) + " orbit(s) could not be fitted");
    if (rank == 0) {
      write_coarse_db(out, db, config_text, ctx.command_line, ctx.options.seed, "msfab-ddfem-build");
      std::filesystem::remove(ckpt);
      double worst = 0, mean = 0;
      for (const auto& [rep, fit] : done) worst = std::max(worst, fit.heldout_error), mean += fit.heldout_error;
      mean /= std::max<std::size_t>(1, done.size());
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf("msfab-ddfem-build: %lld combinations (%d orbits) of %d materials, level 1\n",
                  static_cast<long long>(db.num_combinations()), db.num_orbits, db.num_materials());
      std::printf("  held-out relative energy error: mean %.4f, worst %.4f\n", mean, worst);
      std::printf("  time: %.2f s wall, %.2f s of fitting (%.2f orbits/s per core)\n", wall, fit_seconds,
                  fit_seconds > 0 ? done.size() / fit_seconds : 0.0);
      std::printf("  artifact: %s (%.1f kB)\n", out.c_str(), std::filesystem::file_size(out) / 1024.0);
    }
  });
  MPI_Finalize();
  return code;
}
