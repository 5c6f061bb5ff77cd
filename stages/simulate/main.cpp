// msfab-simulate: nonlinear (or linear) elastostatics of a voxel scene,
// thesis Algorithm 1.
//
//   1. read the scene: grid, palette, layout, boundary conditions, loads
//   2. embed the voxels in a hex mesh (void voxels dropped, nodes shared)
//   3. Newton with line search until the relative residual is small,
//      stepping the load when it is large
//   4. write the `msfab.result` artifact and its ParaView sidecar
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>

#include "cli/progress.hpp"
#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "default_scene.hpp"
#include "result_artifact.hpp"
#include "scene/scene.hpp"

using namespace msfab;

int main(int argc, char** argv) {
  StageApp app("msfab-simulate", "Static elasticity of a voxel scene (Newton with line search, thesis Alg. 1)");
  app.add_common_options();
  app.set_default_config(kDefaultSimulateScene);
  return app.run(argc, argv, [&](StageContext& ctx) {
    const std::string& out = ctx.require_out();
    const auto t0 = std::chrono::steady_clock::now();

    // 1. Scene.
    const Scene scene = read_scene(ctx.config);
    ctx.config.check_no_unknown_keys();

    // 2. Mesh and conditions.
    const VoxelMesh vm = build_voxel_mesh(scene.grid, scene.material_by_id);
    const StaticConditions conditions = build_static_conditions(scene, vm);
    const ElasticAssembler assembler(vm.mesh);
    const double setup = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    spdlog::info("scene '{}': {} x {} x {} grid, {} elements, {} DOFs ({} fixed), {} model", scene.name, scene.grid.nx,
                 scene.grid.ny, scene.grid.nz, vm.mesh.num_elements(), vm.mesh.num_dofs(),
                 conditions.dirichlet.count_fixed(), scene.nonlinear ? "Neo-Hookean" : "linear");

    // 3. Newton.
    NewtonOptions newton = scene.newton;
    Progress progress("load", 100);
    newton.on_load_step = [&](double load) { progress.set(static_cast<std::uint64_t>(100 * load + 0.5)); };
    const NewtonResult result = solve_static(assembler, conditions.dirichlet, conditions.force, newton);
    progress.done();
    if (!result.converged)
      throw NumericalError(result.failure + "\nresidual history:\n" + format_history(result.history));

    // 4. Artifact.
    SimulationRecord record;
    record.scene = &scene;
    record.mesh = &vm;
    record.conditions = &conditions;
    record.newton = &result;
    record.setup_seconds = setup;
    record.config_text = ctx.config.resolved_text();
    record.command_line = ctx.command_line;
    record.seed = ctx.options.seed;
    const std::string xmf = write_result_artifact(out, record);

    double max_u = 0;
    for (int n = 0; n < vm.mesh.num_nodes(); ++n)
      max_u = std::max(max_u, (result.x.segment<3>(3 * n) - vm.mesh.nodes.row(n).transpose()).norm());
    const int its = std::max(1, result.iterations);
    std::printf("msfab-simulate: scene '%s' converged in %d Newton iterations (%d load steps)\n", scene.name.c_str(),
                result.iterations, result.load_steps);
    std::printf("  elements %d, DOFs %d, max displacement %.6g m\n", vm.mesh.num_elements(), vm.mesh.num_dofs(), max_u);
    std::printf("  time: setup %.3f s, assembly %.3f s, solve %.3f s, line search %.3f s (%.3f s per iteration)\n",
                setup, result.timings.assembly, result.timings.solve, result.timings.line_search,
                result.timings.total / its);
    std::printf("  artifact: %s\n  ParaView: %s\n", out.c_str(), xmf.c_str());
  });
}
