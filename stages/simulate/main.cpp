// msfab-simulate: nonlinear (or linear) elastostatics of a voxel scene,
// thesis Algorithm 1, on the fine voxels or coarsened (thesis §2.4).
//
//   1. read the scene: grid, palette, layout, boundary conditions, loads
//   2. embed the voxels in a hex mesh (void voxels dropped, nodes shared)
//   3. with --coarsen L: replace every 2^L block by one coarse element whose
//      materials come from the DDFEM database (or a baseline), and move the
//      conditions onto the coarse mesh
//   4. Newton with line search until the relative residual is small,
//      stepping the load when it is large
//   5. with --compare-fine: also solve the fine model and report the error
//      of the coarse displacements against it (§2.5.2) and the speedup
//   6. write the `msfab.result` artifact and its ParaView sidecar
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>

#include "cli/progress.hpp"
#include "core/timing.hpp"
#include "cli/stage_app.hpp"
#include "coarse_model.hpp"
#include "core/errors.hpp"
#include "ddfem/coarsening_error.hpp"
#include "default_scene.hpp"
#include "result_artifact.hpp"
#include "scene/scene.hpp"

using namespace msfab;

namespace {

NewtonResult solve_or_throw(const ElasticAssembler& assembler, const StaticConditions& conditions,
                            const NewtonOptions& options, const char* label) {
  NewtonOptions newton = options;
  Progress progress(label, 100);
  newton.on_load_step = [&](double load) { progress.set(static_cast<std::uint64_t>(100 * load + 0.5)); };
  NewtonResult result = solve_static(assembler, conditions.dirichlet, conditions.force, newton);
  progress.done();
  if (!result.converged)
    throw NumericalError(std::string(label) + ": " + result.failure + "\nresidual history:\n" +
                         format_history(result.history));
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  StageApp app("msfab-simulate", "Static elasticity of a voxel scene (Newton with line search, thesis Alg. 1)");
  app.add_common_options();
  app.set_default_config(kDefaultSimulateScene);
  CoarseningRequest coarsening;
  bool compare_fine = false;
  app.cli()
      .add_option("--coarsen", coarsening.level, "coarsening levels: 0 (fine), 1 (2x2x2 blocks), 2 (4x4x4)")
      ->check(CLI::Range(0, 2));
  app.cli()
      .add_option("--coarse-material", coarsening.material, "ddfem (needs --database), naive or averaged")
      ->check(CLI::IsMember({"ddfem", "naive", "averaged"}));
  app.cli().add_option("--database", coarsening.database, "coarse_db artifact from msfab-ddfem-build");
  app.cli().add_flag("--compare-fine", compare_fine, "also solve the fine model; report error and speedup");
  std::string reference;
  app.cli().add_option("--reference", reference,
                       "a fine msfab.result of the same scene to compare with instead of solving it again");
  return app.run(argc, argv, [&](StageContext& ctx) {
    const std::string& out = ctx.require_out();
    const auto t0 = std::chrono::steady_clock::now();

    // 1. Scene.
    const Scene scene = read_scene(ctx.config);
    ctx.config.check_no_unknown_keys();

    // 2. Fine mesh and conditions.
    const VoxelMesh fine = build_voxel_mesh(scene.grid, scene.material_by_id);
    const StaticConditions fine_conditions = build_static_conditions(scene, fine);

    // 3. Coarse model.
    CoarseModel coarse;
    if (coarsening.level > 0) coarse = build_coarse_model(scene, fine, coarsening);
    const bool coarsened = coarsening.level > 0;
    const VoxelMesh& vm = coarsened ? coarse.mesh : fine;
    const StaticConditions& conditions = coarsened ? coarse.conditions : fine_conditions;
    const ElasticAssembler assembler(vm.mesh);
    const double setup = seconds_since(t0);
    spdlog::info("scene '{}': {} x {} x {} grid, {} elements, {} DOFs ({} fixed), {} model", scene.name, scene.grid.nx,
                 scene.grid.ny, scene.grid.nz, vm.mesh.num_elements(), vm.mesh.num_dofs(),
                 conditions.dirichlet.count_fixed(), scene.nonlinear ? "Neo-Hookean" : "linear");
    if (coarsened)
      spdlog::info("coarsened to level {} with {} materials: {} -> {} elements, {} distinct blocks, {:.1f} ms{}",
                   coarsening.level, coarsening.material, fine.mesh.num_elements(), vm.mesh.num_elements(),
                   coarse.stats.distinct_combinations, 1e3 * coarse.seconds,
                   coarse.fallback_blocks ? fmt::format(" ({} block kinds without a database fit coarsened naively)",
                                                        coarse.fallback_blocks)
                                          : std::string());

    // 4. Newton.
    const NewtonResult result = solve_or_throw(assembler, conditions, scene.newton, coarsened ? "coarse load" : "load");

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
      VecX uc = result.x;
      for (int n = 0; n < vm.mesh.num_nodes(); ++n) uc.segment<3>(3 * n) -= vm.mesh.nodes.row(n).transpose();
      record.compared = true;
      record.error_vs_fine = mean_vertex_error(scene.grid, fine, uf, coarse.grid, vm, uc);
    }

    // 6. Artifact.
    record.scene = &scene;
    record.mesh = &vm;
    record.conditions = &conditions;
    record.newton = &result;
    record.setup_seconds = setup;
    record.config_text = ctx.config.resolved_text();
    record.command_line = ctx.command_line;
    record.seed = ctx.options.seed;
    if (coarsened) {
      record.coarsen_level = coarsening.level;
      record.coarse_material = coarsening.material;
      record.database = coarsening.database;
      record.coarsening_seconds = coarse.seconds;
      record.fine_elements = fine.mesh.num_elements();
    }
    const std::string xmf = write_result_artifact(out, record);

    double max_u = 0;
    for (int n = 0; n < vm.mesh.num_nodes(); ++n)
      max_u = std::max(max_u, (result.x.segment<3>(3 * n) - vm.mesh.nodes.row(n).transpose()).norm());
    const int its = std::max(1, result.iterations);
    std::printf("msfab-simulate: scene '%s' converged in %d Newton iterations (%d load steps)\n", scene.name.c_str(),
                result.iterations, result.load_steps);
    std::printf("  elements %d, DOFs %d, max displacement %.6g m\n", vm.mesh.num_elements(), vm.mesh.num_dofs(), max_u);
    if (coarsened)
      std::printf("  coarsening: level %d, %s materials, %d -> %d elements, %.3f ms\n", coarsening.level,
                  coarsening.material.c_str(), fine.mesh.num_elements(), vm.mesh.num_elements(),
                  1e3 * coarse.seconds);
    std::printf("  time: setup %.3f s, assembly %.3f s, solve %.3f s, line search %.3f s (%.3f s per iteration)\n",
                setup, result.timings.assembly, result.timings.solve, result.timings.line_search,
                result.timings.total / its);
    if (record.compared)
      std::printf("  vs fine: error %.4e, Newton time fine %.3f s / coarse %.3f s = speedup %.1fx\n",
                  record.error_vs_fine, record.fine_seconds, result.timings.total,
                  record.fine_seconds / result.timings.total);
    std::printf("  artifact: %s\n  ParaView: %s\n", out.c_str(), xmf.c_str());
  });
}
