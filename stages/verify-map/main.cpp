// msfab-verify-map: the full-resolution check of a mapped design (thesis
// §3.6, Table 3.1). The same object under the same supports and loads is
// simulated twice with linear elasticity:
//
//   1. homogenized: the design grid, each cell with the homogenized
//      stiffness of the structure mapped to it
//   2. full resolution: the voxel model of the mapping (r^3 voxels per
//      cell), base material in solid voxels; void carries no unknowns
//      (pieces its supports do not hold are removed and reported), or is
//      an ersatz material void_ratio x stiff (void: ersatz)
//
// Supports and loads of the coarse nodes are carried to the fine grid
// (common/verify/refinement.hpp), the fine displacement is sampled at the
// coarse nodes, and per load case the mean displacement difference and the
// strain-energy difference are reported, written to `msfab.verify_map` and
// summarized on one line (docs/verify_map.md).
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "core/timing.hpp"
#include "io/artifact.hpp"
#include "io/linear_solver_config.hpp"
#include "io/sha256.hpp"
#include "models.hpp"
#include "topopt/edge_joints.hpp"
#include "topopt/grid_elasticity.hpp"
#include "topopt/topopt_scene.hpp"
#include "verify/refinement.hpp"
#include "verify/solid_pieces.hpp"
#include "verify_report.hpp"

using namespace msfab;

namespace {

constexpr const char* kDefaults = R"(
void: remove             # remove (void carries no unknowns; pieces not held are removed) | ersatz
void_ratio: 1.0e-6       # void: ersatz: void voxels and forced-empty cells are this times the stiff material
fill: mapped             # mapped | solid (every non-empty cell solid in both models: the mesh-only reference)
                         # | tile (every design cell holds structure tile_structure, unshifted: a periodic tiling)
tile_structure: 0        # fill: tile: index into the microstructure set
# linear_solver: auto    # full-resolution model: auto | cholmod | pcg-mg | matrix-free
coarse_space: material   # matrix-free solver: material (coarse nodes copied per piece of material in
                         # their support) | lattice (trilinear hat functions across gaps)
# homogenized_linear_solver: auto  # the design grid: the same kinds
homogenized_elements: 1  # hexahedra per cell edge in the homogenized model (> 1: without most of the coarse mesh's stiffness)
# linear_tolerance: 1.0e-8      # iterative solvers (both models): relative residual
# linear_max_iterations: 10000  # iterative solvers: CG iterations before the check fails
)";

struct Settings {
  bool remove_void = true;
  double void_ratio = 1e-6;
  ModelFill fill = ModelFill::mapped;
  std::string fill_name = "mapped";
  int tile_structure = -1;  // fill: tile
  LinearSolverChoice solver, homogenized_solver;
  bool material_coarse_space = true;
  int homogenized_elements = 1;
};

Settings read_settings(const Config& config, const std::string& solver_option) {
  Settings s;
  s.remove_void = config.one_of("void", {"remove", "ersatz"}) == "remove";
  s.void_ratio = config.get_or<double>("void_ratio", 1e-6);
  if (!(s.void_ratio > 0 && s.void_ratio <= 1)) config.fail("void_ratio", "must be in (0, 1]");
  s.fill_name = config.one_of("fill", {"mapped", "solid", "tile"});
  s.fill = s.fill_name == "solid" ? ModelFill::solid : ModelFill::mapped;
  const int tile = config.get_or<int>("tile_structure", 0);
  if (s.fill_name == "tile") {
    if (tile < 0) config.fail("tile_structure", "must be >= 0");
    s.tile_structure = tile;
  }
  const std::vector<std::string> kinds = {"auto", "cholmod", "pcg-mg", "matrix-free"};
  LinearSolverKeys full_keys;
  full_keys.legacy_kind = "solver";
  full_keys.legacy_tolerance = "tolerance";
  s.solver = read_linear_solver_choice(config, kinds, LinearSolverChoice{}, full_keys);
  if (!solver_option.empty()) override_linear_solver_kind(s.solver, solver_option, kinds, "--solver");
  // The homogenized model's own kind; tolerance and iteration limit are shared.
  LinearSolverKeys homogenized_keys;
  homogenized_keys.kind = "homogenized_linear_solver";
  homogenized_keys.legacy_kind = "homogenized_solver";
  LinearSolverChoice homogenized_defaults = s.solver;
  homogenized_defaults.kind = "auto";
  s.homogenized_solver = read_linear_solver_choice(config, kinds, homogenized_defaults, homogenized_keys);
  s.material_coarse_space = config.one_of("coarse_space", {"material", "lattice"}) == "material";
  s.homogenized_elements = config.get_or<int>("homogenized_elements", 1);
  if (s.homogenized_elements < 1 || s.homogenized_elements > 64) config.fail("homogenized_elements", "must be 1..64");
  return s;
}

std::string grid_text(int nx, int ny, int nz) {
  return std::to_string(nx) + " x " + std::to_string(ny) + " x " + std::to_string(nz);
}

// The mapping must describe the design's grid, and index the given set.
void check_inputs(const Design& design, const std::string& design_path, const MappedDesign& mapped,
                  const std::string& mapped_path, const MicrostructureSet& set, const std::string& structures_path) {
  if (design.dimension != 3)
    throw InputError(design_path + ": a " + std::to_string(design.dimension) + "D design (" +
                     grid_text(design.nx, design.ny, design.nz) +
                     " cells); the full-resolution check needs a 3D design");
  if (mapped.dimension != 3 || mapped.nx != design.nx || mapped.ny != design.ny || mapped.nz != design.nz)
    throw InputError(mapped_path + ": attribute 'grid' is " + grid_text(mapped.nx, mapped.ny, mapped.nz) +
                     " cells, the design " + design_path + " has " + grid_text(design.nx, design.ny, design.nz));
  if (std::abs(mapped.cell_size - design.cell_size) > 1e-12 * design.cell_size)
    throw InputError(mapped_path + ": attribute 'cell_size' is " + std::to_string(mapped.cell_size) +
                     ", the design's is " + std::to_string(design.cell_size) + " (" + design_path + ")");
  for (std::int64_t c = 0; c < design.cells(); ++c)
    if (mapped.roles[std::size_t(c)] != design.roles[std::size_t(c)])
      throw InputError(mapped_path + ": /cells/role of cell " + std::to_string(c) + " differs from the design's (" +
                       design_path + ")");
  if (mapped.space != set.space)
    throw InputError(structures_path + ": microstructure space '" + set.space + "' differs from the mapping's '" +
                     mapped.space + "' (" + mapped_path + ")");
  if (set.nx != set.ny || set.ny != set.nz)
    throw InputError(structures_path + ": structures of " + grid_text(set.nx, set.ny, set.nz) +
                     " voxels; the full-resolution model needs cubic voxels (as many per edge on every axis)");
  // Structure indices mean nothing in another set: compare content hashes.
  const std::vector<ArtifactInput> inputs = ArtifactReader(mapped_path, kMappedSchema, kMappedSchemaVersion).inputs();
  const std::string set_hash = sha256_file_hex(structures_path);
  const bool set_known =
      std::any_of(inputs.begin(), inputs.end(), [&](const ArtifactInput& i) { return i.sha256 == set_hash; });
  if (!set_known)
    throw InputError(mapped_path + ": was not mapped with " + structures_path + " (its attribute 'inputs' lists " +
                     (inputs.size() > 1 ? inputs[1].path : std::string("no structures")) +
                     " with another SHA-256); pass the microstructures artifact the mapping used");
  const std::string design_hash = sha256_file_hex(design_path);
  if (std::none_of(inputs.begin(), inputs.end(), [&](const ArtifactInput& i) { return i.sha256 == design_hash; }))
    spdlog::warn("{}: was mapped from another design file than {} (grid and roles agree; checking anyway)", mapped_path,
                 design_path);
}

// The scene: --scene, or the config the design was optimized with.
TopoptScene scene_for(const std::string& scene_path, const Design& design, const std::string& design_path) {
  const Config config =
      scene_path.empty()
          ? Config::from_string(ArtifactReader(design_path, kDesignSchema, kDesignSchemaVersion).config(),
                                design_path + " (attribute 'config')")
          : Config::load_file(scene_path);
  TopoptScene scene = read_topopt_scene(config, design.E_stiff, design.decades);
  const CellGrid& g = scene.setup.grid;
  if (g.dimension() != 3 || g.nx() != design.nx || g.ny() != design.ny || g.nz() != design.nz)
    config.fail("grid.size", "is " + grid_text(g.nx(), g.ny(), g.nz()) + " cells, the design " + design_path + " has " +
                                 grid_text(design.nx, design.ny, design.nz));
  if (std::abs(g.h() - design.cell_size) > 1e-12 * design.cell_size)
    config.fail("grid.cell_size", "is " + std::to_string(g.h()) + ", the design's is " +
                                      std::to_string(design.cell_size) + " (" + design_path + ")");
  for (std::int64_t c = 0; c < g.cells(); ++c)
    if (scene.setup.roles[std::size_t(c)] != design.roles[std::size_t(c)])
      config.fail("domain", "gives cell " + std::to_string(c) + " another role than the design " + design_path);
  return scene;
}

bool all_finite(const VecX& v) { return v.allFinite(); }

// The homogenized model without void (docs/verify_map.md, "Void"): pieces
// of non-empty cells the supports do not hold are removed, nodes only empty
// cells touch are fixed.
void remove_void_from_cells(const CellGrid& grid, std::vector<char>& solid, std::vector<char>& fixed,
                            VerifyReport& report, const std::string& design_path) {
  const PieceRemoval removal = remove_unheld_pieces(grid, solid, fixed);
  if (removal.kept_cells == 0)
    throw InputError(design_path +
                     ": the scene's supports hold none of the design's non-empty cells (every "
                     "piece of them can move freely); nothing to check");
  report.pieces_homogenized = removal.pieces;
  report.removed_pieces_homogenized = removal.removed;
  report.removed_cells_homogenized = removal.removed_cells;
  report.inactive_nodes_homogenized = fix_unknowns_without_material(grid, solid_nodes(grid, solid), fixed);
  if (removal.removed > 0)
    spdlog::warn(
        "homogenized model: {} of {} pieces of cells are not held by the supports and were removed ({} "
        "hexahedra)",
        removal.removed, removal.pieces, removal.removed_cells);
}

// The same for the voxel model. Removing a piece can move a point support
// (it had been moved onto that piece's material), so the supports are
// carried over again until nothing more is removed.
void remove_void_from_voxels(const CellRefinement& refinement, const std::vector<char>& coarse_fixed,
                             std::vector<char>& voxel_material, std::vector<char>& node_material,
                             CellRefinement::Supports& supports, VerifyReport& report, const std::string& mapped_path) {
  for (int pass = 0;; ++pass) {
    const PieceRemoval removal = remove_unheld_pieces(refinement.fine(), voxel_material, supports.fixed);
    if (pass == 0) report.pieces_full = removal.pieces;
    report.removed_pieces_full += removal.removed;
    report.removed_voxels_full += removal.removed_cells;
    if (removal.kept_cells == 0)
      throw InputError(mapped_path + ": the scene's supports hold none of the voxel model's " +
                       std::to_string(removal.pieces) + " pieces (each can move freely); nothing to check");
    if (removal.removed == 0) break;
    node_material = refinement.material_nodes(voxel_material);
    supports = refinement.refine_supports(coarse_fixed, node_material);
  }
  report.inactive_nodes_full = fix_unknowns_without_material(refinement.fine(), node_material, supports.fixed);
  if (report.removed_pieces_full > 0)
    spdlog::warn(
        "full-resolution model: {} of {} pieces are not held by the supports (floating, or held at a point "
        "or along a line) and were removed: {} voxels, {:.2f}% of the material",
        report.removed_pieces_full, report.pieces_full, report.removed_voxels_full,
        100.0 * double(report.removed_voxels_full) / double(std::max<std::int64_t>(report.material_voxels, 1)));
}

// GridElasticity, with a solver the grid does not allow reported against
// the key that chose it.
std::unique_ptr<GridElasticity> make_model(const CellGrid& grid, std::vector<char> fixed,
                                           const LinearSolverChoice& solver, LinearSolverOptions options,
                                           bool material_coarse_space = false) {
  options.pcg_tolerance = solver.tolerance;
  options.pcg_max_iterations = solver.max_iterations;
  options.pcg_max_iterations_key = solver.max_iterations_key;
  try {
    return std::make_unique<GridElasticity>(grid, std::move(fixed), solver.kind, options, material_coarse_space);
  } catch (const InputError& e) {
    throw InputError(solver.kind_key + " = " + solver.kind + ": " + e.what());
  }
}

}  // namespace

int main(int argc, char** argv) {
  StageApp app("msfab-verify-map",
               "Homogenized against full-resolution simulation of a mapped design (thesis 3.6, Table 3.1)");
  app.add_common_options();
  app.set_default_config(kDefaults);
  std::string design_path, mapped_path, structures_path, scene_path, solver_option;
  app.option("--design", design_path, "msfab.design artifact (3D)").type_name("FILE").required();
  app.option("--mapped", mapped_path, "msfab.mapped artifact of that design").type_name("FILE").required();
  app.option("--structures", structures_path, "the msfab.microstructures artifact the mapping used")
      .type_name("FILE")
      .required();
  app.option("--scene", scene_path, "topopt scene YAML with the supports and loads (default: the design's own config)")
      .type_name("FILE");
  app.option("--solver", solver_option, "linear solver of the full-resolution model (same as --set linear_solver=NAME)")
      .type_name("NAME");
  return app.run(argc, argv, [&](StageContext& ctx) {
    const auto start = std::chrono::steady_clock::now();
    const Settings settings = read_settings(ctx.config, solver_option);
    ctx.finish_config();
    const std::string out = ctx.require_out();
    ctx.check_out_folder();

    const Design design = read_design_artifact(design_path);
    MappedDesign mapped = read_mapped_artifact(mapped_path);
    const MicrostructureSet set = read_microstructures_artifact(structures_path);
    check_inputs(design, design_path, mapped, mapped_path, set, structures_path);
    if (settings.tile_structure >= 0) {
      // A periodic tiling of one structure: the mapping's choice replaced in every design cell.
      if (std::size_t(settings.tile_structure) >= set.items.size())
        ctx.config.fail("tile_structure", "is " + std::to_string(settings.tile_structure) + ", the set " +
                                              structures_path + " holds " + std::to_string(set.items.size()) +
                                              " structures");
      for (std::int64_t c = 0; c < mapped.cells(); ++c)
        if (mapped.roles[std::size_t(c)] == CellRole::design)
          mapped.structure[std::size_t(c)] = settings.tile_structure, mapped.shift[std::size_t(c)] = 0;
    }
    const TopoptScene scene = scene_for(scene_path, design, design_path);
    const CellGrid& coarse = scene.setup.grid;
    const int r = set.nx * mapped.tiling;  // voxels per cell edge

    LinearSolverOptions solver_options;
    solver_options.threads = ctx.options.threads;

    VerifyReport report;
    report.fill = settings.fill_name;
    report.tile_structure = settings.tile_structure;
    report.grid[0] = coarse.nx(), report.grid[1] = coarse.ny(), report.grid[2] = coarse.nz();
    report.cell_size = coarse.h();
    report.resolution = r;
    report.tiling = mapped.tiling;
    report.void_ratio = settings.remove_void ? 0.0 : settings.void_ratio;
    report.void_model = settings.remove_void ? "remove" : "ersatz";

    // The homogenized model.
    const ModelMaterials materials = model_materials(set, report.void_ratio);
    // With homogenized_elements = m each cell is m^3 hexahedra of its C^H,
    // its supports and loads carried over as to the voxel model.
    const int m = settings.homogenized_elements;
    const CellRefinement split(coarse, m);
    const CellGrid& hgrid = split.fine();
    const std::vector<char> everywhere(std::size_t(hgrid.nodes()), 1);
    const CellRefinement::Supports hsupports =
        m > 1 ? split.refine_supports(scene.setup.fixed, everywhere) : CellRefinement::Supports();
    std::vector<char> hfixed = m > 1 ? hsupports.fixed : scene.setup.fixed;
    std::vector<char> hsolid(std::size_t(hgrid.cells()));
    for (std::int64_t e = 0; e < hgrid.cells(); ++e) {
      const auto q = hgrid.cell_coords(e);
      hsolid[std::size_t(e)] =
          mapped.roles[std::size_t(coarse.cell_index(q[0] / m, q[1] / m, q[2] / m))] != CellRole::empty;
    }
    if (settings.remove_void) remove_void_from_cells(hgrid, hsolid, hfixed, report, design_path);
    const auto homogenized_model =
        make_model(hgrid, hfixed, settings.homogenized_solver, solver_options, settings.material_coarse_space);
    GridElasticity& homogenized = *homogenized_model;
    {
      const MatX cell_pairs = homogenized_pairs(coarse, mapped, set, materials, settings.fill);
      const EdgeJoints joints = find_edge_joints(coarse, cell_pairs);
      report.edge_joints = joints.count, report.edge_joint_largest_ratio = joints.largest_ratio;
      if (joints.count > 0)
        spdlog::warn(
            "{} edge joint(s): pairs of cells that meet only along an edge, both at least 10x stiffer than "
            "the cells between them (largest ratio {:.3g}); the homogenized model holds such a joint stiffer "
            "than the print, more so the finer the voxels (docs/topopt.md, \"Edge joints\")",
            joints.count, joints.largest_ratio);
      MatX pairs(hgrid.cells(), cell_pairs.cols());
      for (std::int64_t e = 0; e < hgrid.cells(); ++e) {
        const auto q = hgrid.cell_coords(e);
        pairs.row(e) = cell_pairs.row(coarse.cell_index(q[0] / m, q[1] / m, q[2] / m));
        if (settings.remove_void && !hsolid[std::size_t(e)]) pairs.row(e).setZero();
      }
      homogenized.set_stiffness(pairs);
    }
    report.solver_homogenized = homogenized.solver_name();
    report.unknowns_homogenized = hgrid.unknowns();
    report.homogenized_elements = m;
    report.seconds_factorize_homogenized = homogenized.stats().assemble_seconds + homogenized.stats().factorize_seconds;

    // The full-resolution model.
    const auto model_start = std::chrono::steady_clock::now();
    std::vector<std::uint8_t> voxels;
    try {
      voxels = model_voxels(mapped, set, settings.fill);
    } catch (const InputError& e) {
      throw InputError(mapped_path + ": " + e.what() + " (" + structures_path + ")");
    }
    const CellRefinement refinement(coarse, r);
    const CellGrid& fine = refinement.fine();
    // A soft material that is void has no stiffness: with void removed it is void.
    const bool soft_is_material = !(settings.remove_void && set.soft_is_void);
    std::vector<char> voxel_material(voxels.size());
    for (std::size_t i = 0; i < voxels.size(); ++i)
      voxel_material[i] = voxels[i] == 1 || (voxels[i] == 2 && soft_is_material);
    report.voxels = std::int64_t(voxels.size());
    report.material_voxels = std::count(voxel_material.begin(), voxel_material.end(), char(1));
    std::vector<char> node_material = refinement.material_nodes(voxel_material);
    CellRefinement::Supports supports = refinement.refine_supports(scene.setup.fixed, node_material);
    if (settings.remove_void) {
      remove_void_from_voxels(refinement, scene.setup.fixed, voxel_material, node_material, supports, report,
                              mapped_path);
      for (std::size_t i = 0; i < voxels.size(); ++i)
        if (!voxel_material[i]) voxels[i] = 0;
    }
    report.point_supports = supports.point_supports;
    report.moved_point_supports = supports.moved_point_supports;
    report.lost_point_supports = supports.lost_point_supports;
    if (supports.lost_point_supports > 0)
      spdlog::warn(
          "{} point support(s) find no material within half a cell in the full-resolution model: they "
          "hold only void there",
          supports.lost_point_supports);
    spdlog::info(
        "full-resolution model: {} voxels ({:.1f}% material), {} unknowns ({} nodes without material "
        "fixed)",
        report.voxels, 100.0 * double(report.material_voxels) / double(std::max<std::int64_t>(report.voxels, 1)),
        fine.unknowns(), report.inactive_nodes_full);
    // The model keeps the support flags from here on (one grid-sized copy, not two).
    const auto full_model =
        make_model(fine, std::move(supports.fixed), settings.solver, solver_options, settings.material_coarse_space);
    GridElasticity& full = *full_model;
    if (full.solver_name() == "matrix-free") {
      VoxelStiffnessField field = voxel_field(fine, voxels, materials);
      report.seconds_model = seconds_since(model_start);
      full.set_field(std::move(field));
    } else {
      MatX pairs = voxel_pairs(voxels, materials);
      report.seconds_model = seconds_since(model_start);
      full.set_stiffness(pairs);
    }
    report.solver_full = full.solver_name();
    if (report.solver_full == "matrix-free")
      report.coarse_space_full = settings.material_coarse_space ? "material" : "lattice";
    report.unknowns_full = fine.unknowns();
    report.seconds_factorize_full = full.stats().assemble_seconds + full.stats().factorize_seconds;
    spdlog::info("stiffness: homogenized {} ({:.3f} s), full {} ({:.3f} s)", report.solver_homogenized,
                 report.seconds_factorize_homogenized, report.solver_full, report.seconds_factorize_full);

    // Coarse nodes only empty cells touch are void in both models.
    std::vector<char> coarse_active(std::size_t(coarse.nodes()), 0);
    for (std::int64_t c = 0; c < coarse.cells(); ++c)
      if (mapped.roles[std::size_t(c)] != CellRole::empty)
        for (std::int64_t n : coarse.cell_nodes(c)) coarse_active[std::size_t(n)] = 1;

    for (const LoadCase& load : scene.setup.loads) {
      VerifyCase vc;
      vc.name = load.name;
      const double t_hom0 = homogenized.stats().solve_seconds;
      VecX u_split;
      if (m == 1) {
        u_split = homogenized.solve(load.force, load.prescribed);
      } else {
        const VecX prescribed =
            load.prescribed.size() == coarse.unknowns() ? VecX(hsupports.values * load.prescribed) : VecX();
        u_split =
            homogenized.solve(split.refine_forces(load.force, everywhere, "load case '" + load.name + "'"), prescribed);
      }
      vc.solve_seconds_homogenized = homogenized.stats().solve_seconds - t_hom0;
      VecX u_hom(coarse.unknowns());
      for (std::int64_t n = 0; n < coarse.nodes(); ++n)
        u_hom.segment<3>(n * 3) = u_split.segment<3>(split.fine_node_of(n) * 3);
      CellRefinement::LoadStats load_stats;
      VecX fine_force =
          refinement.refine_forces(load.force, node_material, "load case '" + load.name + "'", &load_stats);
      const VecX fine_prescribed =
          load.prescribed.size() == coarse.unknowns() ? VecX(supports.values * load.prescribed) : VecX();
      const double t_full0 = full.stats().solve_seconds;
      const long long it0 = full.stats().iterations;
      const VecX u_full = full.solve(std::move(fine_force), fine_prescribed);
      vc.solve_seconds_full = full.stats().solve_seconds - t_full0;
      vc.iterations_full = full.stats().iterations - it0;
      if (!all_finite(u_split) || !all_finite(u_full))
        throw NumericalError("load case '" + load.name + "': the displacement is not finite");
      vc.point_loads = load_stats.point_loads;
      vc.load_fallbacks = load_stats.fallbacks;
      vc.loaded_fine_nodes = load_stats.fine_nodes;
      vc.homogenized = Eigen::Map<const MatX>(u_hom.data(), 3, coarse.nodes()).transpose();
      vc.displacement = compare_displacements(refinement, u_hom, u_full, node_material, coarse_active);
      vc.energy_homogenized = homogenized.energy(u_split);
      vc.energy_full = full.energy(u_full);
      vc.relative_energy = relative_difference(vc.energy_homogenized, vc.energy_full);
      if (!std::isfinite(vc.relative_energy) || !std::isfinite(vc.displacement.relative))
        throw NumericalError("load case '" + load.name + "': the homogenized model has no strain energy");
      spdlog::info(
          "load case '{}': mean |u| homogenized {:.4g}, full {:.4g}, mean |du| {:.4g} ({:.2f}%) over {} "
          "nodes ({} sampled off the node); energy homogenized {:.4g}, full {:.4g} ({:.2f}%); solve "
          "{:.3f} s / {:.3f} s ({} CG iterations)",
          load.name, vc.displacement.mean_homogenized, vc.displacement.mean_full, vc.displacement.mean_difference,
          100 * vc.displacement.relative, vc.displacement.compared, vc.displacement.nearest, vc.energy_homogenized,
          vc.energy_full, 100 * vc.relative_energy, vc.solve_seconds_homogenized, vc.solve_seconds_full,
          vc.iterations_full);
      if (vc.load_fallbacks > 0)
        spdlog::warn(
            "load case '{}': {} coarse load(s) found only void on their face or edge and were spread over "
            "the nearby material instead",
            load.name, vc.load_fallbacks);
      report.cases.push_back(std::move(vc));
    }
    report.seconds_total = seconds_since(start);
    write_verify_report(out, report, "msfab-verify-map", ctx.config.resolved_text(),
                        scene_path.empty()
                            ? std::vector<std::string>{design_path, mapped_path, structures_path}
                            : std::vector<std::string>{design_path, mapped_path, structures_path, scene_path},
                        ctx.options.seed);

    std::string cases;
    double full_solve = 0, hom_solve = 0;
    for (const VerifyCase& c : report.cases) {
      char buf[256];
      std::snprintf(buf, sizeof buf, "; %s: displacement %.2f%%, energy %.2f%%", c.name.c_str(),
                    100 * c.displacement.relative, 100 * c.relative_energy);
      cases += buf;
      full_solve += c.solve_seconds_full;
      hom_solve += c.solve_seconds_homogenized;
    }
    const std::string elements = m > 1 ? ", " + std::to_string(m) + "^3 elements per cell" : "";
    const std::string tiles = mapped.tiling > 1 ? ", " + std::to_string(mapped.tiling) + "^3 copies per cell" : "";
    std::printf(
        "msfab-verify-map: %d x %d x %d cells, %lld voxels (%d^3 per cell%s, fill %s)%s; homogenized %.3f s "
        "(%s%s), full %.3f s (%s, %lld unknowns); %s\n",
        coarse.nx(), coarse.ny(), coarse.nz(), static_cast<long long>(report.voxels), r, tiles.c_str(),
        report.fill.c_str(), cases.c_str(), report.seconds_factorize_homogenized + hom_solve,
        report.solver_homogenized.c_str(), elements.c_str(), report.seconds_factorize_full + full_solve,
        report.solver_full.c_str(), static_cast<long long>(report.unknowns_full), out.c_str());
    std::printf("  edge joints: %lld (largest stiffness ratio across an edge %.3g)\n",
                static_cast<long long>(report.edge_joints), report.edge_joint_largest_ratio);
  });
}
