#include "adaptive_model.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/timing.hpp"
#include "ddfem/baseline_coarsening.hpp"
#include "ddfem/coarsening_error.hpp"
#include "static_solve.hpp"

namespace msfab {

namespace {

using Rows3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

// The materials of the uniform models: the databases' lookups with the
// level-2 model's element, fallback and check.
CoarseMaterialLookup level1_lookup(const Scene& scene, const CoarseModel& level2, const CoarseDatabase& level1_db) {
  return ddfem_lookup(level1_db, scene.material_by_id, level2.level1, 1, level2, nullptr);
}

CoarseMaterialLookup level2_lookup(const Scene& scene, const CoarseModel& level2) {
  return ddfem_lookup(*level2.database, scene.material_by_id, level2.level1, 2, level2, nullptr);
}

// `lookup` answering first from a uniform model's own materials (its mesh
// holds one per combination of its grid, in order): the mixed meshes take
// the same materials, and a checked lookup homogenizes its block, so each
// block is looked up once per run instead of once per mesh.
CoarseMaterialLookup reusing_materials_of(const CoarseModel& model, CoarseMaterialLookup lookup) {
  auto known = std::make_shared<std::map<ChildIds, QuadratureMaterials>>();
  const auto& materials = model.mesh.mesh.materials;
  if (materials.size() == model.grid.combinations.size())
    for (size_t c = 0; c < materials.size(); ++c) known->emplace(model.grid.combinations[c], materials[c]);
  return [known, lookup = std::move(lookup)](const ChildIds& ids) {
    auto it = known->find(ids);
    if (it == known->end()) it = known->emplace(ids, lookup(ids)).first;
    return it->second;
  };
}

// Displacements of a coarse solution (positions x) interpolated to the fine nodes.
VecX on_fine_nodes(const Scene& scene, const VoxelMesh& fine, const CoarseModel& model, const VecX& x) {
  VecX u = x;
  const HexMesh& mesh = model.mesh.mesh;
  for (int n = 0; n < mesh.num_nodes(); ++n) u.segment<3>(3 * n) -= mesh.nodes.row(n).transpose();
  return interpolate_to_fine(scene.grid, fine, model.grid, model.mesh, u);
}

// A per-unknown vector (3 entries per unknown node) placed on the mesh nodes
// that carry the unknowns, zero on hanging nodes.
template <typename T, typename Vector>
std::vector<T> on_mesh_nodes(const MixedLevelMesh& mixed, const Vector& per_unknown) {
  std::vector<T> out(3 * size_t(mixed.mesh.num_nodes()), T(0));
  for (int u = 0; u < mixed.num_unknown_nodes(); ++u)
    for (int a = 0; a < 3; ++a) out[3 * size_t(mixed.unknown_node[u]) + a] = per_unknown[3 * size_t(u) + a];
  return out;
}

VecX as_vecx(const std::vector<double>& v) { return Eigen::Map<const VecX>(v.data(), VecX::Index(v.size())); }

}  // namespace

VecX adaptive_displacement_on_fine(const Scene& scene, const VoxelMesh& fine, const AdaptiveModel& model,
                                   const ElasticAssembler& assembler, const VecX& x) {
  const VecX u = x - assembler.rest_positions();
  const SpMat W = mixed_to_fine_interpolation(scene.grid, fine, model.mixed);
  VecX out(fine.mesh.num_dofs());
  Eigen::Map<Rows3>(out.data(), fine.mesh.num_nodes(), 3) =
      W * Eigen::Map<const Rows3>(u.data(), model.mixed.num_unknown_nodes(), 3);
  return out;
}

AdaptiveResultOnMesh adaptive_result_on_mesh(const AdaptiveModel& model, const ElasticAssembler& assembler,
                                             const NewtonResult& result) {
  AdaptiveResultOnMesh r;
  r.mesh.mesh = model.mixed.mesh;
  r.conditions.force = as_vecx(on_mesh_nodes<double>(model.mixed, model.conditions.force));
  r.conditions.dirichlet.fixed = on_mesh_nodes<char>(model.mixed, model.conditions.dirichlet.fixed);
  r.conditions.dirichlet.displacement =
      as_vecx(on_mesh_nodes<double>(model.mixed, model.conditions.dirichlet.displacement));
  r.newton = result;
  r.newton.x = assembler.mesh_positions(result.x);
  return r;
}

CoarseModel level1_model_of(const Scene& scene, const VoxelMesh& fine, const CoarseModel& level2,
                            const CoarseDatabase& level1_db) {
  if (!level2.database || level2.database->level != 2)
    throw InputError("--target-error needs --coarse-material ddfem and a level-2 --database");
  const auto t0 = std::chrono::steady_clock::now();
  CoarseModel m;
  m.database = level2.database;
  m.level1 = level2.level1;
  m.grid = level2.level1;
  m.element = level2.element;
  m.fallback = level2.fallback;
  m.check_tolerance = level2.check_tolerance;
  m.mesh = build_coarse_mesh(m.grid, level1_lookup(scene, level2, level1_db), 0, &m.stats, m.element == "enhanced");
  m.conditions = coarse_static_conditions(scene, fine, m.grid, m.mesh);
  m.seconds = seconds_since(t0);
  return m;
}

VecX start_from(const CoarseModel& from, const VecX& x_from, const NodeArray& rest) {
  VecX x = uniform_displacement_at(from.grid, from.mesh, x_from, rest);
  Eigen::Map<Rows3>(x.data(), rest.rows(), 3) += rest;
  return x;
}

namespace {

// Meshes `choice` as the levels of `m`. A node the scene fixes must not
// hang on free corners: the cells around it are meshed fine (face
// conditions fix whole faces, so this is rare).
void mesh_chosen_levels(AdaptiveModel& m, const Scene& scene, const VoxelMesh& fine,
                        const StaticConditions& fine_conditions, const CoarseModel& level2, LevelChoice choice) {
  m.choice = std::move(choice);
  m.cells_refined_for_conditions = 0;
  std::vector<int>& levels = m.choice.cell_level;
  for (;;) {
    m.mixed = build_mixed_level_mesh(scene.grid, scene.material_by_id, level2.level1, level2.grid, levels,
                                     m.level1_materials, m.level2_materials, level2.element == "enhanced");
    std::vector<int> unresolved;
    m.conditions =
        mixed_static_conditions(scene, fine, fine_conditions, level2.level1, level2.grid, m.mixed, &unresolved);
    int changed = 0;
    for (int c : unresolved)
      if (levels[c] != 0) {
        levels[c] = 0;
        ++changed;
      }
    if (changed == 0) break;
    m.cells_refined_for_conditions += changed;
  }
  m.choice.predicted_error = predicted_error(m.cells, m.level_errors, levels);
}

}  // namespace

void rechoose_adaptive_levels(AdaptiveModel& m, const Scene& scene, const VoxelMesh& fine,
                              const StaticConditions& fine_conditions, const CoarseModel& level2,
                              double choice_target) {
  const auto t0 = std::chrono::steady_clock::now();
  // A re-choice must refine some cell of the choice it replaces (the caller
  // solves again because that one missed): where the tightened target
  // refines none, it is halved until one is.
  const std::vector<int> previous = m.choice.cell_level;
  auto refines_a_cell = [&](const std::vector<int>& levels) {
    for (size_t c = 0; c < levels.size(); ++c)
      if (levels[c] < previous[c]) return true;
    return false;
  };
  LevelChoice choice = choose_cell_levels(m.cells, m.level_errors, choice_target);
  for (int halvings = 0; !previous.empty() && !refines_a_cell(choice.cell_level) && halvings < 30; ++halvings) {
    choice_target *= 0.5;
    choice = choose_cell_levels(m.cells, m.level_errors, choice_target);
  }
  // Cells an earlier re-choice refined further (with calibrated level
  // errors) stay so.
  if (!previous.empty())
    for (size_t c = 0; c < previous.size(); ++c) choice.cell_level[c] = std::min(choice.cell_level[c], previous[c]);
  m.choice_target = choice_target;
  mesh_chosen_levels(m, scene, fine, fine_conditions, level2, std::move(choice));
  m.seconds += seconds_since(t0);
}

bool rechoose_where_measured(AdaptiveModel& m, const Scene& scene, const VoxelMesh& fine,
                             const StaticConditions& fine_conditions, const CoarseModel& level2, const VecX& on_fine,
                             const PosteriorEstimate& measured, double target_error) {
  if (measured.error_field.size() == 0) return false;
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<double> energies = cell_field_energies(fine, level2.grid, on_fine, measured.error_field);
  const LevelErrors calibrated =
      calibrated_level_errors(m.cells, m.level_errors, m.choice.cell_level, energies, measured.value);
  LevelChoice choice = refine_cell_levels(m.cells, calibrated, m.choice.cell_level, target_error);
  if (choice.cell_level == m.choice.cell_level) return false;
  // The model keeps its a-priori errors (the artifact's, and the ratio of
  // predictions the refinement bound takes); the a-priori target these
  // levels meet is what a later tightened re-choice starts from.
  m.choice_target = predicted_error(m.cells, m.level_errors, choice.cell_level);
  mesh_chosen_levels(m, scene, fine, fine_conditions, level2, std::move(choice));
  m.seconds += seconds_since(t0);
  return true;
}

AdaptiveModel build_adaptive_model(const Scene& scene, const VoxelMesh& fine, const StaticConditions& fine_conditions,
                                   const CoarseModel& level2, const VecX& x2, const CoarseModel& level1, const VecX& x1,
                                   const CoarseDatabase& level1_db, double target_error) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!level2.database || level2.database->level != 2)
    throw InputError("--target-error needs --coarse-material ddfem and a level-2 --database");
  AdaptiveModel m;

  // The estimate: the two uniform solutions' difference, energies of the finer one.
  const VecX u1 = on_fine_nodes(scene, fine, level1, x1);
  const VecX u2 = on_fine_nodes(scene, fine, level2, x2);
  m.level_difference = mean_vertex_error(fine.mesh, u1, u2);
  // Richardson: with e_L ~ C h^p, u_fine ~ u1 + (u1 - u2) / (2^p - 1); the
  // same rate as the level errors, so that both estimates agree on uniform
  // choices.
  const double rate = 1.0;
  m.level_errors = level_errors_from_difference(m.level_difference, rate);
  m.extrapolated = u1 + (u1 - u2) / (std::pow(2.0, rate) - 1.0);
  m.level1_materials = reusing_materials_of(level1, level1_lookup(scene, level2, level1_db));
  m.level2_materials = reusing_materials_of(level2, level2_lookup(scene, level2));
  m.cells =
      cell_error_models(scene.grid, level2.level1, level2.grid, level1.mesh, element_energies(level1.mesh.mesh, x1));
  m.seconds = seconds_since(t0);
  rechoose_adaptive_levels(m, scene, fine, fine_conditions, level2, target_error);
  return m;
}

double a_posteriori_error(const VoxelMesh& fine, const AdaptiveModel& model, const VecX& u_on_fine) {
  return mean_vertex_error(fine.mesh, model.extrapolated, u_on_fine);
}

double refinement_error_bound(const VoxelMesh& fine, const VecX& finer_on_fine, double finer_predicted,
                              const VecX& coarser_on_fine, double coarser_predicted) {
  if (!(coarser_predicted > 0)) return std::numeric_limits<double>::infinity();
  // Near rho = 1 the factor rho / (1 - rho) magnifies any error in the
  // predicted ratio (its derivative is 1 / (1 - rho)^2): only a refinement
  // that was chosen to at least halve the error gives a bound.
  const double rho = std::max(finer_predicted, 0.0) / coarser_predicted;
  if (!(rho <= 0.5)) return std::numeric_limits<double>::infinity();
  return rho / (1 - rho) * mean_vertex_error(fine.mesh, coarser_on_fine, finer_on_fine);
}

PosteriorEstimate posterior_estimate(const VoxelMesh& fine, const AdaptiveModel& model, const VecX& on_fine,
                                     const VecX* previous_on_fine, double previous_predicted, int previous_solve) {
  const auto& per_level = model.mixed.elements_per_level;
  if (per_level[1] == 0 && per_level[2] == 0) return {0.0, "the fine model"};
  const double extrapolated = a_posteriori_error(fine, model, on_fine);
  const double bound = previous_on_fine ? refinement_error_bound(fine, on_fine, model.choice.predicted_error,
                                                                 *previous_on_fine, previous_predicted)
                                        : std::numeric_limits<double>::infinity();
  if (bound < extrapolated)
    return {bound, fmt::format("from the change since solve {}, extrapolation {:.3g}", previous_solve, extrapolated)};
  return {extrapolated, "against the extrapolation"};
}

PosteriorEstimate fine_newton_estimate(const VoxelMesh& fine, const ElasticAssembler& fine_assembler,
                                       const StaticConditions& fine_conditions, const NewtonOptions& options,
                                       const AdaptiveModel& model, const VecX& on_fine) {
  const auto& per_level = model.mixed.elements_per_level;
  if (per_level[1] == 0 && per_level[2] == 0) return {0.0, "the fine model"};
  const NewtonStepFrom newton = newton_step_from(fine_assembler, fine_conditions.dirichlet, fine_conditions.force,
                                                 options, fine_assembler.rest_positions() + on_fine);
  if (!newton.failure.empty()) return {0.0, "no fine Newton step: " + newton.failure, false};
  if (newton.shift > 0)
    return {0.0, fmt::format("the fine tangent there is not positive definite (shift {:.2e} needed)", newton.shift),
            false};
  const VecX zero = VecX::Zero(newton.step.size());
  const double size = mean_vertex_error(fine.mesh, newton.step, zero);
  if (!newton.indefinite) return {size, "a fine Newton step", true, newton.step};
  // An indefinite tangent amplifies the step along its soft directions (one
  // step measured up to 1.26x the true error on the ten scenes): a second
  // step from where the first lands corrects the estimate to third order.
  // Steps towards the minimum the fine solve finds lower the potential at
  // each step and shrink; where one raises it (or inverts an element), they
  // follow a direction of negative curvature elsewhere (skeleton at 0.02:
  // 19x the true error) and say nothing about the error.
  const std::string indefinite = "the fine tangent there is indefinite";
  const auto potential = [&](const VecX& u) {
    return fine_assembler.evaluate(fine_assembler.rest_positions() + u, nullptr, nullptr) -
           fine_conditions.force.dot(u);
  };
  const auto no_descent = [&](const std::string& potentials) {
    return PosteriorEstimate{
        0.0, fmt::format("{}, and Newton steps from it do not lower the potential ({})", indefinite, potentials),
        false};
  };
  const double p0 = potential(on_fine), p1 = potential(VecX(on_fine + newton.step));
  if (!(p1 < p0)) return no_descent(fmt::format("{:.4g}, then {:.4g}", p0, p1));
  const NewtonStepFrom second = newton_step_from(fine_assembler, fine_conditions.dirichlet, fine_conditions.force,
                                                 options, fine_assembler.rest_positions() + on_fine + newton.step);
  if (!second.failure.empty()) return {0.0, indefinite + "; no second step: " + second.failure, false};
  const double p2 = potential(VecX(on_fine + newton.step + second.step));
  if (!(p2 < p1)) return no_descent(fmt::format("{:.4g}, {:.4g}, then {:.4g}", p0, p1, p2));
  const double second_size = mean_vertex_error(fine.mesh, second.step, zero);
  // Steps that converge shrink; a longer second step has not reached the
  // minimum's neighbourhood (the demo bar at 0.01: 2.0e-3, then 4.8e-3).
  if (!(second_size < size))
    return {0.0,
            fmt::format("{}, and the second Newton step from it is not shorter than the first ({:.3g}, then {:.3g})",
                        indefinite, size, second_size),
            false};
  const VecX both = newton.step + second.step;
  return {mean_vertex_error(fine.mesh, both, zero),
          fmt::format("two fine Newton steps, {:.3g} then {:.3g}; {}{}", size, second_size, indefinite,
                      second.indefinite ? ", also after the first step" : ""),
          true, both};
}

AdaptiveRun solve_adaptively(const Scene& scene, const VoxelMesh& fine, const StaticConditions& fine_conditions,
                             const CoarseModel& coarse, const CoarseDatabase& level1_db,
                             const AdaptiveRunOptions& options) {
  AdaptiveRun run;
  // Each finer solve starts from the coarser solution, at full load: a few
  // Newton steps instead of the scene's load stepping from rest.
  NewtonOptions warm = scene.newton;
  warm.load_steps = 1;
  const NewtonResult solve2 =
      solve_or_throw(ElasticAssembler(coarse.mesh.mesh), coarse.conditions, scene.newton, "level-2 load");
  const CoarseModel level1 = level1_model_of(scene, fine, coarse, level1_db);
  const NewtonResult solve1 = solve_or_throw(ElasticAssembler(level1.mesh.mesh), level1.conditions, warm,
                                             "level-1 load", start_from(coarse, solve2.x, level1.mesh.mesh.nodes));
  run.uniform_seconds = solve2.timings.total + solve1.timings.total;
  AdaptiveModel adapted =
      build_adaptive_model(scene, fine, fine_conditions, coarse, solve2.x, level1, solve1.x, level1_db, options.target);
  // The mixed solve and, with --posterior-check, its a-posteriori check.
  // Its linear solver follows the size rule of every static solve: the
  // lattice multigrid takes elements of mixed sizes, whose nodes sit on
  // the fine lattice (docs/solvers.md). A miss refines the cells where
  // the estimate puts the error, or tightens the target of the choice by
  // the ratio it missed by, and solves again.
  // The solves are ranked by their estimates (kept_solve): an
  // extrapolated estimate is raised to the fine Newton estimate of a
  // solve that refines it, since the extrapolation cannot see the error
  // both uniform levels share. A refinement whose extrapolated estimate
  // does not come down means the extrapolation, not the model,
  // dominates it (where the error falls much faster than the rate
  // assumed, the extrapolated solution is itself off): the loop stops.
  // A measured estimate that does not come down is a model that needs
  // more refinement, which the next round gives from those levels.
  // After a refinement the estimate is also bounded by how far the solve
  // moved from the previous one (posterior_estimate).
  std::optional<ElasticAssembler> fine_assembler;
  if (options.newton_estimate) fine_assembler.emplace(fine.mesh);
  struct Round {
    AdaptiveModel model;
    NewtonResult result;
    std::string source;
  };
  std::vector<Round> rounds;
  std::vector<CheckedSolve> checked;
  std::size_t kept = 0;  // into rounds and checked
  VecX previous_on_fine;
  double previous_predicted = 0;
  for (;;) {
    // A choice of level-2 cells only is the uniform level-2 model: its
    // solution is the start, and Newton has nothing left to do.
    const ElasticAssembler mixed_assembler(adapted.mixed.mesh, adapted.mixed.constraints);
    const bool all_level2 = adapted.mixed.elements_per_level[0] == 0 && adapted.mixed.elements_per_level[1] == 0;
    const NodeArray& unknown_rest = adapted.mixed.constraints->unknown_rest;
    const NewtonResult solved = solve_or_throw(
        mixed_assembler, adapted.conditions, warm, "adaptive load",
        all_level2 ? start_from(coarse, solve2.x, unknown_rest) : start_from(level1, solve1.x, unknown_rest));
    ++run.solves;
    const VecX on_fine = adaptive_displacement_on_fine(scene, fine, adapted, mixed_assembler, solved.x);
    // The fine model's own estimate where its tangent allows one, else
    // the extrapolation's.
    PosteriorEstimate posterior{0.0, "", false};
    if (options.newton_estimate)
      posterior = fine_newton_estimate(fine, *fine_assembler, fine_conditions, scene.newton, adapted, on_fine);
    const bool measured = posterior.measured;
    if (!measured) {
      const std::string no_newton = posterior.source;
      posterior = posterior_estimate(fine, adapted, on_fine, run.solves > 1 ? &previous_on_fine : nullptr,
                                     previous_predicted, run.solves - 1);
      if (options.newton_estimate) posterior.source += " (no Newton estimate: " + no_newton + ")";
    }
    const double estimate = posterior.value;
    previous_on_fine = on_fine;
    previous_predicted = adapted.choice.predicted_error;
    spdlog::info(
        "adaptive solve {}: levels chosen for {:.3g} (predicted {:.3g}), a-posteriori estimate {:.3g} "
        "({}) against the target {:.3g}; elements fine {} / level 1 {} / level 2 {}",
        run.solves, adapted.choice_target, adapted.choice.predicted_error, estimate, posterior.source, options.target,
        adapted.mixed.elements_per_level[0], adapted.mixed.elements_per_level[1], adapted.mixed.elements_per_level[2]);
    checked.push_back({adapted.choice.cell_level, estimate, measured});
    rounds.push_back({adapted, solved, posterior.source});
    kept = kept_solve(checked);
    run.estimate = ranked_estimate(checked, kept);
    if (run.estimate > checked[kept].estimate)
      spdlog::info(
          "adaptive: solve {}'s extrapolated estimate {:.3g} is raised to {:.3g}, the fine Newton estimate of "
          "a solve that refines it",
          kept + 1, checked[kept].estimate, run.estimate);
    if (!options.posterior_check || run.estimate <= options.target) break;
    // A new solve can only raise the earlier ones' ranks, so it lowered the
    // smallest estimate exactly when it is the one kept.
    const bool improved = kept + 1 == checked.size();
    if ((!improved && !measured) || run.solves == kMaxAdaptiveSolves) {
      spdlog::warn(
          "adaptive: the a-posteriori estimate {:.3g} stays above the target {:.3g} after {} mixed solves; "
          "keeping the solve with the smallest estimate",
          run.estimate, options.target, run.solves);
      break;
    }
    // Where the estimate is a field (fine Newton steps), it calibrates
    // the level-1 and level-2 errors and the levels are refined for the
    // target with them, to fine cells where level 1 falls short; else
    // the a-priori choice is made for a target tightened by the ratio
    // of the miss.
    if (!rechoose_where_measured(adapted, scene, fine, fine_conditions, coarse, on_fine, posterior, options.target))
      rechoose_adaptive_levels(adapted, scene, fine, fine_conditions, coarse,
                               adapted.choice_target * options.target / estimate);
  }
  for (std::size_t r = 0; r < rounds.size(); ++r)
    if (r != kept) run.rejected_seconds += rounds[r].result.timings.total;
  run.result = std::move(rounds[kept].result);
  run.estimate_source = rounds[kept].source;
  if (run.estimate > checked[kept].estimate)
    run.estimate_source +=
        fmt::format(", raised from {:.3g} to the fine Newton estimate of a refinement", checked[kept].estimate);
  run.model = std::move(rounds[kept].model);
  return run;
}

}  // namespace msfab
