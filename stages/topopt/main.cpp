// msfab-topopt: two-scale topology optimization inside a material gamut
// (thesis §3.4, Eq. 3.5-3.9), with the SIMP baselines of §3.6.2.
//
//   1. read the scene: grid, design domain, supports, load cases, mass terms
//   2. the material space: a gamut level set (cubic3d, cubic2d,
//      orthotropic2d; isotropic inside a cubic gamut), a family's own
//      parameters (family3d), the analytic gamut E <= rho^3 E0, or SIMP
//      E = rho^p E0
//   3. the start: uniform rho inside the space, or a coarser design
//      (coarse-to-fine continuation, §3.6.3)
//   4. minimize S(p, u) s.t. K(p) u = f (adjoint), Phi(p_i) <= 0 and the
//      Voigt bound C(p_i) <= rho_i C_stiff per cell, with Ipopt
//      (limited-memory Hessian) or, for large grids, MMA with a subproblem
//      that separates over the cells; SIMP by optimality criteria or MMA
//   5. write `msfab.design` with its ParaView sidecar
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "design_report.hpp"
#include "design_start.hpp"
#include "gamut/gamut_artifact.hpp"
#include "gamut/microstructure_set.hpp"
#include "topopt/cell_mma.hpp"
#include "topopt/edge_joints.hpp"
#include "topopt/family_material.hpp"
#include "topopt/simp_mma.hpp"
#include "topopt/topology_optimizers.hpp"
#include "topopt/topopt_scene.hpp"
#include "verify/design_refinement.hpp"

using namespace msfab;

namespace {

// Peak memory of an optimization on a grid, measured with /usr/bin/time
// (docs/cli.md, "Memory"): 2D grids are solved by CHOLMOD, about
// 265 n log2(n) bytes for n cells (4.3 kB per cell at 512 x 256); 3D grids
// with the default solvers about 5 kB per finite element (1.13 GB for cell
// MMA at 128 x 64 x 32). Read before the scene, so that a grid that cannot
// fit is refused before its per-cell arrays are allocated.
void check_grid_memory(const StageContext& ctx, const Config& config) {
  const ConfigGridSize size = config_grid_size(config);
  if (size.counts.empty()) return;  // read_topopt_scene names the missing key
  const int m = std::clamp(config.get_or<int>("elements_per_cell", 1), 1, 8);
  const double elements = size.cells * (size.counts.size() == 3 ? double(m) * m * m : 1.0);
  const double bytes = size.counts.size() == 2 ? 265.0 * elements * std::log2(std::max(elements, 2.0)) : 5e3 * elements;
  ctx.check_memory(bytes,
                   "a grid of " + size.text + " cells (grid.size)" +
                       (m > 1 ? " with elements_per_cell " + std::to_string(m) : std::string()),
                   "use a coarser grid");
}
// A 2D cantilever (Fig. 3-16's loading): left side clamped, a downward load
// spread over the right half of the bottom side; SIMP p = 3 needs no gamut.
constexpr const char* kDefaults = R"(
grid: {size: [48, 24], cell_size: 1.0}
space: simp2d
material: {E: 1.0, nu: 0.3, penalty: 3}
supports: [{box: {min: [0, 0], max: [0, 24]}}]
loads:
  - {name: bottom, objective: compliance,
     forces: [{box: {min: [24, 0], max: [48, 0]}, force: [0, -1], distribute: total}]}
mass: {volume_fraction: 0.5}
filter: {radius: 1.5}
optimizer: {name: auto, max_iterations: 500}
)";
}  // namespace

int main(int argc, char** argv) {
  StageApp app("msfab-topopt", "Two-scale topology optimization in a material gamut (thesis 3.4)");
  app.add_common_options();
  app.set_default_config(kDefaults);
  return app.run(argc, argv, [&](StageContext& ctx) {
    const std::string& out = ctx.require_out();
    Config& config = ctx.config;

    // 2. The material space (its gamut first: it sets E0 and the normalization).
    Gamut gamut;
    std::vector<std::string> inputs;
    const std::string space = config.one_of("space", cell_material_spaces());
    const std::string needs = required_gamut_space(space);
    if (!needs.empty()) {
      if (!config.has("gamut")) config.fail("gamut", "is missing: space " + space + " needs a gamut artifact");
      const std::string path = config.get_path("gamut");
      gamut = read_gamut_artifact(path);
      if (gamut.space != needs)
        config.fail("gamut", path + " is a " + gamut.space + " gamut; space " + space + " needs a " + needs + " gamut");
      inputs.push_back(path);
      // The level set's zero lies `padding` outside the outermost samples;
      // subtracting it leaves the optimizer only properties structures have.
      if (config.has("gamut_padding") && config.one_of("gamut_padding", {"keep", "subtract"}) == "subtract") {
        const double padding = gamut.level_set.padding();
        gamut.level_set = gamut.level_set.shifted(padding);
        spdlog::info("gamut constraint moved inward by its padding: Phi + {:.4g} <= 0", padding);
      }
    } else if (config.has("gamut")) {
      config.fail("gamut", "space " + space + " takes no gamut");
    }
    // A family space reads the family's structure grid instead; its base
    // material sets E0 and the normalization as a gamut's does.
    MicrostructureSet family;
    std::string family_path;
    if (needs_family_grid(space)) {
      if (!config.has("family"))
        config.fail("family",
                    "is missing: space " + space + " needs a family's structures (msfab-family-generate, grid:)");
      family_path = config.get_path("family");
      family = read_microstructures_artifact(family_path);
      inputs.push_back(family_path);
      gamut.E_stiff = family.E_stiff;
      gamut.decades = family.decades;
      if (config.has("gamut_padding")) config.fail("gamut_padding", "space " + space + " takes no gamut");
    } else if (config.has("family")) {
      config.fail("family", "is read by the family3d space only");
    } else if (config.has("gamut_padding")) {
      config.fail("gamut_padding", "space " + space + " takes no gamut");
    }
    // The Voigt bound (topopt/voigt_bound.hpp): no structure is stiffer than
    // its base materials' volume average, whatever the level set allows.
    const bool bound_asked = config.has("gamut_bound");
    const bool use_bound = bound_asked ? config.one_of("gamut_bound", {"voigt", "none"}) == "voigt" : !needs.empty();
    if (bound_asked && needs.empty()) config.fail("gamut_bound", "space " + space + " takes no gamut");
    if (use_bound && gamut.bound_stiff.size() == 0) {
      if (bound_asked)
        config.fail("gamut_bound", config.get_path("gamut") + " stores no base materials (/bound); sample it again");
      spdlog::warn("{}: no base materials stored (/bound), so the Voigt bound is not applied; sample it again",
                   config.get_path("gamut"));
    }

    // 1. The scene (its size checked against memory before anything is
    // allocated per cell).
    check_grid_memory(ctx, config);
    const TopoptScene scene = read_topopt_scene(config, gamut.E_stiff, gamut.decades);
    if (!family_path.empty() && std::abs(scene.nu - family.stiff.nu) > 1e-12)
      config.fail("material.nu", "is " + std::to_string(scene.nu) + " but the family's base material has " +
                                     std::to_string(family.stiff.nu));
    CellMaterialSettings ms{scene.space,
                            scene.E0,
                            scene.decades,
                            scene.nu,
                            scene.penalty,
                            scene.E_min_ratio,
                            needs.empty() ? nullptr : &gamut.level_set};
    // Regularization: cell-mma smooths the gradient as the thesis does
    // (`filter.kind: smoothing`) or, in spaces without per-cell
    // constraints, filters the parameters (`density`: family3d then derives
    // each cell's rho from its family parameters); ipopt always filters.
    const std::string optimizer = config.has("optimizer.name")
                                      ? config.one_of("optimizer.name", {"auto", "ipopt", "oc", "mma", "cell-mma"})
                                      : "auto";
    const bool use_cell_mma = optimizer == "cell-mma";
    const bool density_filter =
        config.has("filter.kind") && config.one_of("filter.kind", {"smoothing", "density"}) == "density";
    if (config.has("filter.kind") && !use_cell_mma)
      config.fail("filter.kind", "is read by the cell-mma optimizer only (ipopt, oc and mma filter the parameters)");
    const auto model = family_path.empty() ? make_cell_material_model(ms)
                                           : make_family_material_model(family, family_path, density_filter);
    if (use_bound && gamut.bound_stiff.size() > 0) model->set_voigt_bound(gamut.bound_stiff, gamut.bound_soft);
    if (density_filter && (model->has_constraint() || model->bound_conditions() > 0))
      config.fail("filter.kind",
                  "density needs a space without per-cell constraints (family3d, simp2d, simp3d); space " + space +
                      " has them, so cell-mma smooths its gradient instead");

    OptimizerSettings os;
    os.max_iterations = config.get_or<int>("optimizer.max_iterations", 500);
    if (os.max_iterations < 1) config.fail("optimizer.max_iterations", "must be >= 1");
    os.tolerance = config.get_or<double>("optimizer.tolerance", os.tolerance);
    if (!(os.tolerance > 0 && os.tolerance < 1)) config.fail("optimizer.tolerance", "must be in (0, 1)");
    os.constraint_tolerance = config.get_or<double>("optimizer.constraint_tolerance", os.constraint_tolerance);
    if (!(os.constraint_tolerance > 0)) config.fail("optimizer.constraint_tolerance", "must be > 0");
    os.change_tolerance = config.get_or<double>("optimizer.change_tolerance", os.change_tolerance);
    if (!(os.change_tolerance >= 0 && os.change_tolerance < 1))
      config.fail("optimizer.change_tolerance", "must be in [0, 1) (0: run max_iterations)");
    const bool use_oc = optimizer == "oc" || (optimizer == "auto" && model->parameters() == 1);
    const bool use_mma = optimizer == "mma";
    const std::string chosen = use_oc ? "oc" : use_mma ? "mma" : use_cell_mma ? "cell-mma" : "ipopt";
    if (config.has("optimizer.move")) {
      if (!use_cell_mma) config.fail("optimizer.move", "is read by the cell-mma optimizer only");
      os.mma_move = config.get<double>("optimizer.move");
      if (!(os.mma_move > 0 && os.mma_move <= 1)) config.fail("optimizer.move", "must be in (0, 1]");
    }
    if ((use_oc || use_mma) && model->parameters() != 1)
      config.fail("optimizer.name", chosen + " is for the simp spaces (simp2d, simp3d); space " + space + " has " +
                                        std::to_string(model->parameters()) +
                                        " parameters per cell (use ipopt or cell-mma)");
    const CellGrid& grid = scene.setup.grid;
    os.mass_limit = scene.volume_fraction > 0;
    os.mass_budget = scene.volume_fraction * grid.cell_volume() * double(grid.cells());
    if ((use_oc || use_mma) && !os.mass_limit)
      config.fail("mass.volume_fraction", "the " + chosen + " optimizer needs a volume fraction > 0");

    // 3. The start.
    const DesignStart start = read_design_start(config, *model, grid);
    if (!start.path.empty()) inputs.push_back(start.path);
    ctx.finish_config();
    ctx.check_out_folder();

    TopologySetup setup = scene.setup;
    setup.solver_options.threads = ctx.options.threads;
    refine_fem_mesh(setup, scene.elements_per_cell);
    // cell-mma's default regularization smooths the gradient
    // (topopt/cell_mma.hpp): its cells' parameters are then the physical ones.
    const double smoothing_radius = use_cell_mma && !density_filter ? setup.filter_radius : 0.0;
    if (use_cell_mma && !density_filter) setup.filter_radius = 0;
    TopologyObjective objective(setup, *model);
    const CellFilter smoothing(grid, objective.design_cells(), smoothing_radius);
    const MatX q0 = start.rows(objective.design_cells());
    spdlog::info(
        "{}D grid {} x {} x {} ({} design cells; {}^{} elements per cell, {} unknowns), space {} ({} parameters), "
        "{} load case(s), solver {}, optimizer {}",
        grid.dimension(), grid.nx(), grid.ny(), grid.nz(), objective.design_cells().size(), scene.elements_per_cell,
        grid.dimension(), objective.fem_grid().unknowns(), space, model->parameters(), setup.loads.size(),
        objective.elasticity().solver_name(), chosen);

    // 4. Optimize.
    os.log_every = 10;
    const OptimizationResult r = use_oc         ? optimize_oc(objective, q0, os)
                                 : use_mma      ? optimize_mma(objective, q0, os)
                                 : use_cell_mma ? optimize_cell_mma(objective, q0, os, smoothing)
                                                : optimize_in_gamut(objective, q0, os);

    // 5. Report and artifact.
    const Design design = make_design(objective, r, gamut.E_stiff > 0 ? gamut.E_stiff : scene.E0, scene.decades);
    write_design_artifact(out, design, "msfab-topopt", config.resolved_text(), inputs, ctx.options.seed);
    const GridSolveStats& st = objective.elasticity().stats();
    std::printf("msfab-topopt: %s after %d iterations (%d objective evaluations), %.2f s\n", r.status.c_str(),
                r.iterations, r.evaluations, r.seconds);
    std::printf("  objective %.6e (elastic %.6e, mass terms %.3e)\n", r.value.total, r.value.elastic, r.value.mass);
    for (std::size_t l = 0; l < setup.loads.size(); ++l)
      std::printf("  load case %s: %s %.6e\n", setup.loads[l].name.c_str(),
                  setup.loads[l].objective == ElasticObjective::compliance ? "compliance" : "target error",
                  r.value.per_load[l]);
    if (r.update_seconds > 0)
      std::printf("  optimizer's own work (subproblems): %.2f s of %.2f s (%.3f s per iteration)\n", r.update_seconds,
                  r.seconds, r.update_seconds / std::max(1, r.iterations));
    std::printf("  mass fraction %.4f, max constraint %.3e\n",
                objective.mass(r.q) / (grid.cell_volume() * double(grid.cells())), r.max_violation);
    const EdgeJoints joints = find_edge_joints(grid, objective.cell_pairs(objective.physical(r.q)));
    std::printf(
        "  edge joints: %lld (pairs of cells meeting only along an edge, or at a corner in 2D, both >= 10x "
        "stiffer than the cells between them; largest ratio %.3g)\n",
        static_cast<long long>(joints.count), joints.largest_ratio);
    const double per = 1.0 / std::max(1, st.factorizations);
    std::printf(
        "  FEM: %d factorizations, %d solves (%s), %.3f s per factorization+solve (assembly %.3f, "
        "factorization %.3f, solves %.3f)\n",
        st.factorizations, st.solves, objective.elasticity().solver_name().c_str(),
        (st.assemble_seconds + st.factorize_seconds + st.solve_seconds) * per, st.assemble_seconds * per,
        st.factorize_seconds * per, st.solve_seconds * per);
    if (st.iterations > 0) std::printf("  CG iterations per solve: %.1f\n", double(st.iterations) / st.solves);
    std::printf("  artifact: %s\n", out.c_str());
  });
}
