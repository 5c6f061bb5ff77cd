// msfab-fill-targets: generate microstructures at the targets of an
// optimized design that its microstructure set does not cover, so that the
// mapper (msfab-map) finds a structure near every cell's stiffness instead
// of a far neighbour. MPI-parallel.
//
//   1. coverage: per design cell, the smallest property gap
//      |C(structure) - C(target)|_F / |C(target)|_F among its k nearest
//      structures (the mapper's candidates)
//   2. targets: the cells above `gap`, worst first, each with the
//      uncovered cells within cluster_radius (unit cube) of it; one target
//      per group at the group's mean properties
//   3. per target, spread over ranks and threads: the continuous step of
//      the gamut sampler (thesis §3.2.2, Eq. 3.4) from the `starts`
//      structures of smallest gap, aimed at the target's compliance and
//      density; the grey optimum thresholded at several levels, each
//      printable candidate (mirrored, cleaned, no feature below
//      min_feature) homogenized; the structure of smallest gap is kept
//      if it is closer than any structure the set had
//   4. repeat for `rounds` (later rounds also start from the new
//      structures); write the set with the new structures appended (step
//      `targeted`, parent its start): the input structures keep their
//      indices
//
// Every target's work is deterministic and independent of the others, so
// the result is the same for any rank or thread count.
#include <omp.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>

#include "cli/progress.hpp"
#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "core/timing.hpp"
#include "homog/periodic_homogenization.hpp"
#include "mapping/mapper.hpp"
#include "mapping/set_lineage.hpp"
#include "mapping/target_fill.hpp"
#include "parallel/fan_out.hpp"
#include "parallel/mpi_session.hpp"

using namespace msfab;

namespace {

constexpr const char* kDefaults = R"(
gap: 0.1                # a cell is covered when one of its candidates is this close (relative, Frobenius norm of C)
candidates: 16          # nearest structures per cell, as msfab-map's candidates
match: all              # as msfab-map's: all properties, or stiffness (moduli and Poisson ratios, not the density)
starts: 2               # refinement starts per target: the structures of smallest gap
cluster_radius: 0.02    # uncovered cells this close (unit cube) share one target
max_targets: 256        # per round; the largest gaps first
rounds: 2
void_stiffness: 1.0e-6  # as the gamut sampler's
min_feature: 1          # the printer's minimum feature in voxels
connector: {half_width: 0, depth: 1}  # > 0: every structure gets a solid patch at each face centre (2 half_width voxels wide)
refine: {max_iterations: 60, penalty: 3, filter_radius: 1.5, density_weight: 1.0, start_offset: 0.3, projection_beta: 8,
         threshold_levels: [0.5, 0.4, 0.45, 0.55, 0.6]}
)";

ContinuousOptions default_refine() {
  ContinuousOptions k;
  k.max_iterations = 60;
  k.projection_beta = 8;
  k.threshold_levels = {0.5, 0.4, 0.45, 0.55, 0.6};
  return k;
}

struct Settings {
  FillPlanOptions plan;
  int connector_half_width = 0, connector_depth = 1;
  int rounds = 2;
  double void_stiffness = 1e-6;
  ContinuousOptions refine = default_refine();
};

Settings read_settings(const Config& config) {
  Settings s;
  s.plan.gap = config.get_or<double>("gap", 0.1);
  if (!(s.plan.gap > 0 && s.plan.gap < 1e3)) config.fail("gap", "must be in (0, 1000)");
  s.plan.candidates.k = config.get_or<int>("candidates", 16);
  if (s.plan.candidates.k < 1 || s.plan.candidates.k > 4096) config.fail("candidates", "must be 1..4096");
  s.plan.candidates.stiffness_only = read_stiffness_only(config);
  s.plan.starts = config.get_or<int>("starts", 2);
  if (s.plan.starts < 1 || s.plan.starts > s.plan.candidates.k) config.fail("starts", "must be 1..candidates");
  s.plan.cluster_radius = config.get_or<double>("cluster_radius", 0.02);
  if (!(s.plan.cluster_radius >= 0 && s.plan.cluster_radius <= 2)) config.fail("cluster_radius", "must be in [0, 2]");
  s.plan.max_targets = config.get_or<int>("max_targets", 256);
  if (s.plan.max_targets < 0 || s.plan.max_targets > 100000) config.fail("max_targets", "must be 0..100000");
  s.rounds = config.get_or<int>("rounds", 2);
  if (s.rounds < 0 || s.rounds > 100) config.fail("rounds", "must be 0..100");
  s.void_stiffness = config.get_or<double>("void_stiffness", 1e-6);
  if (!(s.void_stiffness > 0 && s.void_stiffness < 1e-2)) config.fail("void_stiffness", "must be in (0, 0.01)");
  if (config.has("connector")) {
    const Config c = config.child("connector");
    s.connector_half_width = c.get_or<int>("half_width", 0);
    if (s.connector_half_width < 0 || s.connector_half_width > 2048) c.fail("half_width", "must be 0..2048");
    s.connector_depth = c.get_or<int>("depth", 1);
    if (s.connector_depth < 1 || s.connector_depth > 2048) c.fail("depth", "must be 1..2048");
  }
  ContinuousOptions& k = s.refine;
  k.min_feature = config.get_or<int>("min_feature", 1);
  if (k.min_feature < 1 || k.min_feature > 64) config.fail("min_feature", "must be 1..64");
  if (!config.has("refine")) return s;
  const Config r = config.child("refine");
  k.max_iterations = r.get_or<int>("max_iterations", k.max_iterations);
  if (k.max_iterations < 1 || k.max_iterations > 10000) r.fail("max_iterations", "must be 1..10000");
  k.penalty = r.get_or<double>("penalty", k.penalty);
  if (!(k.penalty >= 1 && k.penalty <= 10)) r.fail("penalty", "must be in [1, 10]");
  k.filter_radius = r.get_or<double>("filter_radius", k.filter_radius);
  if (!(k.filter_radius >= 0 && k.filter_radius <= 8)) r.fail("filter_radius", "must be in [0, 8]");
  k.density_weight = r.get_or<double>("density_weight", k.density_weight);
  if (!(k.density_weight >= 0 && k.density_weight <= 1e6)) r.fail("density_weight", "must be in [0, 1e6]");
  k.start_offset = r.get_or<double>("start_offset", k.start_offset);
  if (!(k.start_offset >= 0 && k.start_offset < 0.5)) r.fail("start_offset", "must be in [0, 0.5)");
  k.projection_beta = r.get_or<double>("projection_beta", k.projection_beta);
  if (!(k.projection_beta >= 0 && k.projection_beta <= 1024)) r.fail("projection_beta", "must be in [0, 1024]");
  k.threshold_levels = r.get_or<std::vector<double>>("threshold_levels", k.threshold_levels);
  if (k.threshold_levels.empty() || k.threshold_levels.size() > 64)
    r.fail("threshold_levels", "must hold 1..64 levels");
  for (double level : k.threshold_levels)
    if (!(level > 0 && level < 1)) r.fail("threshold_levels", "every level must lie in (0, 1)");
  return s;
}

void report(const char* when, const CellCoverage& c, double gap) {
  std::printf("  %s: property gap of the best candidate max %.4g, mean %.4g; %lld of %lld cells above %g\n", when,
              c.max_gap, c.mean_gap, static_cast<long long>(c.above(gap)), static_cast<long long>(c.design_cells), gap);
}

}  // namespace

int main(int argc, char** argv) {
  const MpiSession mpi(&argc, &argv);
  const int rank = mpi.rank(), size = mpi.size();
  StageApp app("msfab-fill-targets",
               "Generate microstructures at the design targets its set does not cover (continuous step, thesis 3.2.2)");
  app.set_rank(rank);
  app.add_common_options();
  app.set_default_config(kDefaults);
  std::string design_path, structures_path;
  app.option("--design", design_path, "msfab.design artifact (the optimized cells)").type_name("FILE").required();
  app.option("--structures", structures_path, "msfab.microstructures artifact of the design's space")
      .type_name("FILE")
      .required();
  const int code = app.run(argc, argv, [&](StageContext& ctx) {
    const Settings settings = read_settings(ctx.config);
    ctx.finish_config();
    const std::string& out = ctx.require_out();
    ctx.check_out_folder();
    MicrostructureSet set = read_microstructures_artifact(structures_path);
    const Design design = read_design_artifact(design_path);
    check_mapping_inputs(design, design_path, set, structures_path);
    check_set_belongs_to_design(design_path, structures_path);
    MapperOptions coverage_options;
    coverage_options.candidates = settings.plan.candidates;
    coverage_options.half_shift = false;
    ctx.check_memory(mapping_peak_bytes(design, set, coverage_options) +
                         omp_get_max_threads() * homogenization_peak_bytes(set.nx, set.ny, set.nz, "auto"),
                     "the coverage of " + std::to_string(design.cells()) + " cells and one cell problem of " +
                         std::to_string(set.nx) + "^" + (set.nz > 1 ? "3" : "2") + " voxels per thread",
                     "use fewer threads (OMP_NUM_THREADS) or candidates");
    const auto start = std::chrono::steady_clock::now();
    const std::size_t given = set.items.size();
    set.grid = {};  // generated structures lie off any parameter grid the set had
    if (rank == 0)
      spdlog::info("{}: {} x {} x {} cells; {}: {} structures of {} x {} x {} voxels; {} rank(s) x {} thread(s)",
                   design_path, design.nx, design.ny, design.nz, structures_path, given, set.nx, set.ny, set.nz, size,
                   omp_get_max_threads());

    // 0. On request, a face connector on every structure (generated ones keep it).
    Settings run = settings;
    if (settings.connector_half_width > 0) {
      if (2 * settings.connector_half_width > set.nx || 2 * settings.connector_depth > set.nx)
        ctx.config.fail("connector", "half_width and depth must be at most half the structures' " +
                                         std::to_string(set.nx) + " voxels");
      run.refine.frozen_stiff =
          add_face_connector(set, settings.connector_half_width, settings.connector_depth, settings.void_stiffness);
      if (rank == 0)
        spdlog::info("face connector ({} voxels wide, {} deep) added to the {} structures",
                     2 * settings.connector_half_width, settings.connector_depth, given);
    }
    // 1. Coverage of the given set.
    const CellCoverage before = cell_coverage(design, set, settings.plan.candidates);
    CellCoverage now = before;
    std::vector<std::string> round_lines;
    for (int round = 1; round <= settings.rounds && now.above(settings.plan.gap) > 0; ++round) {
      const auto t_round = std::chrono::steady_clock::now();
      // 2. Targets.
      const std::vector<FillTarget> targets = plan_targets(design, set, now, settings.plan);
      // 3. One structure per target, across ranks and threads.
      Progress progress("round " + std::to_string(round) + ": structures at targets", targets.size());
      const int row = generated_record_size(set);
      const std::vector<double> records = fan_out(static_cast<int>(targets.size()), row, [&](int t, double* r) {
        write_generated_record(generate_at_target(set, targets[std::size_t(t)], run.refine, settings.void_stiffness),
                               r);
        progress.tick();
      });
      progress.done();
      std::vector<GeneratedStructure> generated;
      int found = 0;
      for (std::size_t t = 0; t < targets.size(); ++t) {
        generated.push_back(read_generated_record(set, &records[t * std::size_t(row)]));
        const GeneratedStructure& g = generated.back();
        found += g.found;
        if (rank == 0)
          spdlog::debug(
              "target {} ({} cells, rho {:.3f}): gap of the set {:.4f}; generated {:.4f} (rho {:.3f}, from {})", t,
              targets[t].cells.size(), targets[t].raw[targets[t].raw.size() - 1], targets[t].gap,
              g.found ? g.gap : -1.0, g.rho, g.parent);
      }
      // 4. The new structures, then the coverage they give.
      const int added = append_generated(set, targets, generated, round);
      now = cell_coverage(design, set, settings.plan.candidates);
      char line[256];
      std::snprintf(
          line, sizeof line,
          "  round %d: %zu targets, %d printable, %d added; gap max %.4g, mean %.4g, %lld cells above; %.1f s", round,
          targets.size(), found, added, now.max_gap, now.mean_gap, static_cast<long long>(now.above(settings.plan.gap)),
          seconds_since(t_round));
      round_lines.emplace_back(line);
      if (rank == 0) spdlog::info("{}", line + 2);
      if (added == 0) break;
    }

    if (rank == 0) {
      write_microstructures_artifact(out, set, "msfab-fill-targets", ctx.config.resolved_text(),
                                     {design_path, structures_path}, ctx.options.seed);
      std::printf("msfab-fill-targets: %lld design cells, %zu structures given, %zu generated, %.1f s\n",
                  static_cast<long long>(before.design_cells), given, set.items.size() - given, seconds_since(start));
      report("given set", before, settings.plan.gap);
      for (const std::string& l : round_lines) std::printf("%s\n", l.c_str());
      report("with the new structures", now, settings.plan.gap);
      std::printf("  artifact: %s\n", out.c_str());
    }
  });
  return code;
}
