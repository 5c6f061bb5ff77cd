// msfab-simulate: nonlinear (or linear) elastostatics of a voxel scene,
// thesis Algorithm 1, on the fine voxels or coarsened (thesis §2.4).
//
//   1. read the scene: grid, palette, layout, boundary conditions, loads
//   2. embed the voxels in a hex mesh (void voxels dropped, nodes shared)
//   3. with --coarsen L: replace every 2^L block by one coarse element whose
//      materials come from the DDFEM database (or a baseline), and move the
//      conditions onto the coarse mesh; with --target-error E: solve the
//      uniform level-2 and level-1 models, choose per 4^3 cell between fine,
//      level 1 and level 2 so that the estimated error is at most E, and mesh
//      the scene with those levels (hanging nodes constrained)
//   4. Newton with line search until the relative residual is small,
//      stepping the load when it is large
//   5. with --compare-fine: also solve the fine model and report the error
//      of the coarse displacements against it (§2.5.2) and the speedup
//   6. write the `msfab.result` artifact and its ParaView sidecar
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "adaptive_model.hpp"
#include "cli/progress.hpp"
#include "cli/stage_app.hpp"
#include "coarse_model.hpp"
#include "core/errors.hpp"
#include "core/timing.hpp"
#include "ddfem/coarsening_error.hpp"
#include "ddfem/coarsening_options.hpp"
#include "default_scene.hpp"
#include "result_artifact.hpp"
#include "scene/scene.hpp"
#include "static_solve.hpp"

using namespace msfab;

namespace {

// Elements of the scene's mesh at coarsening level L: the 2^L blocks that
// hold a solid voxel.
double elements_at_level(const VoxelGrid& grid, int level) {
  const int b = 1 << level;
  std::int64_t count = 0;
  for (int k = 0; k < grid.nz; k += b)
    for (int j = 0; j < grid.ny; j += b)
      for (int i = 0; i < grid.nx; i += b) {
        bool solid = false;
        for (int c = k; c < std::min(k + b, grid.nz) && !solid; ++c)
          for (int r = j; r < std::min(j + b, grid.ny) && !solid; ++r)
            for (int q = i; q < std::min(i + b, grid.nx) && !solid; ++q) solid = grid.ids[grid.index(q, r, c)] != 0;
        count += solid;
      }
  return double(count);
}

// The grid's voxel ids are read before anything can be estimated from
// them: refuse a grid that cannot even be held.
void check_grid_memory(const StageContext& ctx) {
  const ConfigGridSize size = config_grid_size(ctx.config);
  ctx.check_memory(sizeof(int) * size.cells, "a grid of " + size.text + " voxels (grid.size)", "use a coarser grid");
}

// The models this run solves: the scene's level (adaptive: levels 2 and
// 1; the mixed mesh chosen from them is not known yet), and the fine one
// when compared.
void check_solve_memory(const StageContext& ctx, const Scene& scene, std::vector<int> levels, bool solves_fine) {
  if (solves_fine && levels.front() > 0) levels.push_back(0);
  double bytes = 0, largest = 0;
  for (int level : levels) {
    const double elements = elements_at_level(scene.grid, level);
    bytes += static_solve_peak_bytes(elements, 3 * elements, scene.newton);
    largest = std::max(largest, elements);
  }
  ctx.check_memory(
      bytes,
      fmt::format("a model of {:.0f} elements ({} solver)", largest, static_linear_solver(3 * largest, scene.newton)),
      levels.front() == 0 ? "coarsen it (--coarsen 1 or 2) or use a coarser grid" : "use a coarser grid");
}

}  // namespace

int main(int argc, char** argv) {
  StageApp app("msfab-simulate", "Static elasticity of a voxel scene (Newton with line search, thesis Alg. 1)");
  app.add_common_options();
  app.set_default_config(kDefaultSimulateScene);
  CoarseningRequest coarsening;
  bool compare_fine = false;
  add_coarsening_options(app, coarsening, true);
  app.flag("--compare-fine", compare_fine, "also solve the fine model; report error and speedup");
  double target_error = 0;
  const StageOption target_option = app.option(
      "--target-error", target_error,
      "adaptive coarsening: the mean-vertex error (thesis 2.5.2) to stay within, choosing fine, level 1 or level 2 "
      "per 4x4x4 cell (needs a level-2 --database)");
  std::string level1_database;
  app.option("--level1-database", level1_database,
             "adaptive coarsening: a level-1 coarse_db of the same palette and element for the level-1 "
             "cells and solve, instead of the level-2 database's compressed level-1 base");
  bool posterior_check = false;
  app.flag("--posterior-check", posterior_check,
           "adaptive coarsening: check the mixed solution against the extrapolated fine one and, where "
           "it misses the target, choose finer levels and solve again (at most 3 mixed solves)");
  std::string posterior_estimator = "extrapolation";
  app.option("--posterior-estimate", posterior_estimator,
             "adaptive coarsening: the a-posteriori estimate of a mixed solve: its distance from the "
             "extrapolated fine solution (extrapolation; free, blind to error the two levels share) or the "
             "size of one Newton step of the fine model from it (newton; one fine tangent solve per check, "
             "sees every error; two exact steps where the fine tangent there is indefinite, the extrapolation where "
             "those do not converge)")
      .one_of({"extrapolation", "newton"});
  std::string reference;
  app.option("--reference", reference,
             "a fine msfab.result of the same scene to compare with instead of solving it again");
  return app.run(argc, argv, [&](StageContext& ctx) {
    const std::string& out = ctx.require_out();
    const auto t0 = std::chrono::steady_clock::now();

    // 1. Scene.
    check_grid_memory(ctx);
    const Scene scene = read_scene(ctx.config);
    ctx.finish_config();
    const bool adaptive = target_option.given();
    if (posterior_check && !adaptive) throw InputError("--posterior-check: applies to --target-error only");
    const bool newton_estimate = posterior_estimator == "newton";
    if (newton_estimate && !adaptive) throw InputError("--posterior-estimate: applies to --target-error only");
    if (!level1_database.empty() && !adaptive)
      throw InputError("--level1-database: applies to --target-error only (uniform level 1 takes --database)");
    check_solve_memory(ctx, scene, adaptive ? std::vector<int>{2, 1} : std::vector<int>{coarsening.level},
                       compare_fine);

    // 2. Fine mesh and conditions.
    const VoxelMesh fine = build_voxel_mesh(scene.grid, scene.material_by_id);
    const StaticConditions fine_conditions = build_static_conditions(scene, fine);

    // 3. Coarse model: uniform, or adaptive from the uniform level-2 and level-1 solves.
    if (adaptive) {
      if (!(target_error > 0) || !std::isfinite(target_error))
        throw InputError("--target-error: must be a finite number > 0 (the mean-vertex error), got " +
                         fmt::format("{}", target_error));
      if (coarsening.level != 0) throw InputError("--target-error chooses the levels itself; drop --coarsen");
      if (coarsening.material != "ddfem")
        throw InputError("--target-error needs --coarse-material ddfem and a level-2 --database");
      if (coarsening.window > 0)
        throw InputError(
            "--target-error: --coarse-window is not supported (the mixed mesh takes one material set "
            "per distinct block, a window needs one per cell); drop it");
      coarsening.level = 2;
    }
    if (coarsening.level == 0 && !coarsening.element.empty())
      throw InputError("--coarse-element: needs --coarsen 1 or 2 (the fine mesh is trilinear)");
    CoarseModel coarse;
    if (coarsening.level > 0) coarse = build_coarse_model(scene, fine, coarsening);
    const bool coarsened = coarsening.level > 0;
    AdaptiveRun adaptive_run;  // adaptive: the kept mixed model, its solve and its check
    const AdaptiveModel& adapted = adaptive_run.model;
    double adaptive_seconds = 0;  // adaptive: everything after the level-2 model, database reading aside
    // Adaptive: the level-1 materials, the level-2 database's own base unless
    // a level-1 database stands in for it. Where the base is compressed, the
    // uniform level-1 and level-2 models share its lookup error, which their
    // difference (the estimate) cannot see (docs/ddfem.md). Kept for the run.
    std::shared_ptr<const CoarseDatabase> level1_db;
    if (adaptive) {
      level1_db = coarse.database->level1;
      if (!level1_database.empty()) {
        auto db = std::make_shared<CoarseDatabase>(read_coarse_db(level1_database));
        check_level1_substitute(*db, level1_database, *coarse.database, coarsening.database);
        level1_db = db;
      }
      const auto t_adaptive = std::chrono::steady_clock::now();
      adaptive_run = solve_adaptively(scene, fine, fine_conditions, coarse, *level1_db,
                                      {target_error, posterior_check, newton_estimate});
      adaptive_seconds = seconds_since(t_adaptive);
    }
    const VoxelMesh& vm = coarsened ? coarse.mesh : fine;
    const HexMesh& solved_mesh = adaptive ? adapted.mixed.mesh : vm.mesh;
    const StaticConditions& conditions = adaptive    ? adapted.conditions
                                         : coarsened ? coarse.conditions
                                                     : fine_conditions;
    const ElasticAssembler assembler =
        adaptive ? ElasticAssembler(solved_mesh, adapted.mixed.constraints) : ElasticAssembler(solved_mesh);
    const double setup = seconds_since(t0);
    spdlog::info("scene '{}': {} x {} x {} grid, {} elements, {} DOFs ({} fixed), {} model", scene.name, scene.grid.nx,
                 scene.grid.ny, scene.grid.nz, solved_mesh.num_elements(), assembler.num_dofs(),
                 conditions.dirichlet.count_fixed(), scene.nonlinear ? "Neo-Hookean" : "linear");
    if (adaptive)
      spdlog::info(
          "adaptive: level-1/level-2 difference {:.3g} (estimated errors {:.3g} / {:.3g}); target {:.3g}, "
          "predicted {:.3g}; elements fine {} / level 1 {} / level 2 {}, {} hanging nodes; uniform solves "
          "{:.3f} s, level choice and mesh {:.3f} s",
          adapted.level_difference, adapted.level_errors[1], adapted.level_errors[2], target_error,
          adapted.choice.predicted_error, adapted.mixed.elements_per_level[0], adapted.mixed.elements_per_level[1],
          adapted.mixed.elements_per_level[2], adapted.mixed.hanging_nodes, adaptive_run.uniform_seconds,
          adapted.seconds);
    else if (coarsened)
      spdlog::info("coarsened to level {} with {} materials: {} -> {} elements, {} distinct blocks, {:.1f} ms{}",
                   coarsening.level, coarsening.material, fine.mesh.num_elements(), vm.mesh.num_elements(),
                   coarse.stats.distinct_combinations, 1e3 * coarse.seconds,
                   coarse.fallback_blocks ? fmt::format(" ({} block kinds without a database fit coarsened {})",
                                                        coarse.fallback_blocks, coarsening.fallback)
                                          : std::string());
    if (coarsened && coarsening.check_tolerance > 0 && coarsening.window == 0)
      spdlog::info(
          "checked lookup: {} of {} solid mixed block kinds had a fit farther than {} from their own "
          "homogenized stiffness and were coarsened by the matched model",
          coarse.replaced_blocks, coarse.checked_blocks, coarsening.check_tolerance);
    if (coarsened && coarsening.check_tolerance > 0 && coarsening.window > 0)
      spdlog::info(
          "checked lookup against windows: {} of {} solid mixed cells had a fit farther than {} from their "
          "stiffness among {} voxels of their neighbours and were coarsened by the windowed matched model",
          coarse.replaced_blocks, coarse.checked_blocks, coarsening.check_tolerance, coarsening.window);
    if (coarsened && coarsening.window > 0)
      spdlog::info(
          "windows: {} distinct among the solid cells, each homogenized once; {} cells kept their own "
          "homogenized stiffness (void in the window, or a stiffness the window does not determine)",
          coarse.distinct_windows, coarse.unresolved_windows);

    // 4. Newton (adaptive: solved above, with its check).
    const NewtonResult result =
        adaptive ? adaptive_run.result
                 : solve_or_throw(assembler, conditions, scene.newton, coarsened ? "coarse load" : "load");
    // The coarse model's Newton time; adaptive runs include the uniform solves.
    const double coarse_seconds =
        result.timings.total +
        (adaptive ? adaptive_run.uniform_seconds + adaptive_run.rejected_seconds + adapted.seconds : 0.0);

    // 5. Fine reference.
    SimulationRecord record;
    if (!reference.empty() && !coarsened) throw InputError("--reference needs --coarsen 1 or 2");
    if (!reference.empty() && compare_fine) throw InputError("--reference and --compare-fine exclude each other");
    if (coarsened && (compare_fine || !reference.empty())) {
      VecX uf;
      if (compare_fine) {
        const ElasticAssembler fine_assembler(fine.mesh);
        const NewtonResult ref = solve_or_throw(fine_assembler, fine_conditions, scene.newton, "fine load");
        uf = ref.x;
        for (int n = 0; n < fine.mesh.num_nodes(); ++n) uf.segment<3>(3 * n) -= fine.mesh.nodes.row(n).transpose();
        record.fine_seconds = ref.timings.total;
      } else {
        const FineReference ref = read_fine_reference(reference, fine);
        uf = ref.displacement;
        record.fine_seconds = ref.newton_seconds;
      }
      record.compared = true;
      record.error_vs_fine =
          adaptive ? mean_vertex_error(fine.mesh, uf,
                                       adaptive_displacement_on_fine(scene, fine, adapted, assembler, result.x))
                   : mean_vertex_error(scene.grid, fine, uf, coarse.grid, vm, result.x - assembler.rest_positions());
      if (!adaptive) {
        const CoarseErrorFloor floor = coarse_error_floor(scene.grid, fine, uf, coarse.grid, vm);
        record.has_error_floor = true;
        record.error_floor = floor.error;
        record.error_floor_lower_bound = floor.lower_bound;
        spdlog::info("error floor: {:.4e} (certified >= {:.4e}) after {} iterations, {:.2f} s", floor.error,
                     floor.lower_bound, floor.iterations, floor.seconds);
      }
    }

    // 6. Artifact (adaptive runs: every node of the mixed mesh, hanging ones interpolated).
    AdaptiveResultOnMesh on_mesh;
    if (adaptive) on_mesh = adaptive_result_on_mesh(adapted, assembler, result);
    record.scene = &scene;
    record.mesh = adaptive ? &on_mesh.mesh : &vm;
    record.conditions = adaptive ? &on_mesh.conditions : &conditions;
    record.newton = adaptive ? &on_mesh.newton : &result;
    record.setup_seconds = setup;
    record.config_text = ctx.config.resolved_text();
    record.command_line = ctx.command_line;
    record.seed = ctx.options.seed;
    record.inputs = scene.geometry_files;
    if (!coarsening.database.empty()) record.inputs.push_back(coarsening.database);
    if (!level1_database.empty()) record.inputs.push_back(level1_database);
    if (!reference.empty()) record.inputs.push_back(reference);
    if (coarsened) {
      record.coarsen_level = coarsening.level;
      record.coarse_material = coarsening.material;
      record.coarse_element = coarse.element;
      if (coarsening.material == "ddfem") {
        record.coarse_fallback = coarsening.fallback;
        record.fallback_blocks = coarse.fallback_blocks;
        record.check_tolerance = coarsening.check_tolerance;
        record.checked_blocks = coarse.checked_blocks;
        record.replaced_blocks = coarse.replaced_blocks;
      }
      record.window = coarsening.window;
      record.unresolved_windows = coarse.unresolved_windows;
      record.distinct_windows = coarse.distinct_windows;
      record.database = coarsening.database;
      record.coarsening_seconds = coarse.seconds;
      record.fine_elements = fine.mesh.num_elements();
    }
    if (adaptive) {
      record.adaptive = true;
      record.target_error = target_error;
      record.predicted_error = adapted.choice.predicted_error;
      record.a_posteriori_error = adaptive_run.estimate;
      record.a_posteriori_source = adaptive_run.estimate_source;
      record.adaptive_solves = adaptive_run.solves;
      record.rejected_solve_seconds = adaptive_run.rejected_seconds;
      record.uniform_solve_seconds = adaptive_run.uniform_seconds;
      record.level_difference = adapted.level_difference;
      record.level1_database = level1_database;
      record.elements_per_level = adapted.mixed.elements_per_level;
      // Besides the Newton solves recorded on their own: the level-1 model,
      // the level choices and mixed meshes, and the a-posteriori estimates.
      record.coarsening_seconds = coarse.seconds + adaptive_seconds - adaptive_run.uniform_seconds -
                                  adaptive_run.rejected_seconds - adaptive_run.result.timings.total;
    }
    const std::string xmf = write_result_artifact(out, record);

    double max_u = 0;
    const VecX u_solved = result.x - assembler.rest_positions();
    for (int n = 0; n < assembler.num_dofs() / 3; ++n) max_u = std::max(max_u, u_solved.segment<3>(3 * n).norm());
    const int its = std::max(1, result.iterations);
    std::printf("msfab-simulate: scene '%s' converged in %d Newton iterations (%d load steps)\n", scene.name.c_str(),
                result.iterations, result.load_steps);
    std::printf("  elements %d, DOFs %d, max displacement %.6g m\n", solved_mesh.num_elements(), assembler.num_dofs(),
                max_u);
    if (adaptive)
      std::printf(
          "  adaptive: target error %.3g, predicted %.3g, a-posteriori %.3g after %d mixed solve(s); elements "
          "fine %d / level 1 %d / level 2 %d (of %d fine); level-1 and level-2 solves %.3f s\n",
          target_error, adapted.choice.predicted_error, adaptive_run.estimate, adaptive_run.solves,
          adapted.mixed.elements_per_level[0], adapted.mixed.elements_per_level[1], adapted.mixed.elements_per_level[2],
          fine.mesh.num_elements(), adaptive_run.uniform_seconds);
    else if (coarsened)
      std::printf("  coarsening: level %d, %s materials, %s elements, %d -> %d elements, %.3f ms\n", coarsening.level,
                  coarsening.material.c_str(), coarse.element.c_str(), fine.mesh.num_elements(), vm.mesh.num_elements(),
                  1e3 * coarse.seconds);
    std::printf("  time: setup %.3f s, assembly %.3f s, solve %.3f s, line search %.3f s (%.3f s per iteration)\n",
                setup, result.timings.assembly, result.timings.solve, result.timings.line_search,
                result.timings.total / its);
    if (record.compared)
      std::printf(
          "  vs fine: error %.4e, Newton time fine %.3f s / coarse %.3f s = speedup %.1fx\n"
          "    (error: mean distance between the fine and the interpolated coarse displacement over the fine "
          "vertices, divided by the longest side of the body, thesis 2.5.2; 1e-2 is 1%% of the body)\n",
          record.error_vs_fine, record.fine_seconds, coarse_seconds, record.fine_seconds / coarse_seconds);
    if (record.has_error_floor)
      std::printf(
          "  best possible on this coarse mesh: error %.4e (the best trilinear fit of the fine displacements)\n",
          record.error_floor);
    std::printf("  artifact: %s\n  ParaView: %s\n", out.c_str(), xmf.c_str());
  });
}
