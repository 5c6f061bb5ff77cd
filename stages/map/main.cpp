// msfab-map: replace every cell of an optimized design by a microstructure
// whose properties match the cell's, choosing among near matches so that
// neighbouring cells line up at their shared faces (thesis §3.5).
//
//   1. candidates: per design cell the k nearest structures to its target
//      in the normalized material space (and all within `radius`), each also
//      translated by half a cell (same properties, another boundary)
//   2. mismatch energy I = sum_i I_i, I_i the boundary voxels of cell i whose
//      id differs from the voxel across the face (forced empty cells void,
//      forced solid cells id 1)
//   3. a random candidate per cell (hash of seed and cell), then greedy
//      descent: the cell with the largest I_i takes the candidate lowering I
//      most, or leaves the list; changed cells' neighbours re-enter it; until
//      no single change lowers I
//   4. write `msfab.mapped`; on request the voxel model as a bit-packed
//      voxel file, per-material STL surfaces and PNG slices, layer by layer
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "core/timing.hpp"
#include "io/path_names.hpp"
#include "mapping/mapper.hpp"
#include "mapping/set_lineage.hpp"
#include "mapping/voxel_model.hpp"

using namespace msfab;

namespace {

constexpr const char* kDefaults = R"(
candidates: 16          # nearest structures per cell
match: all              # candidates by all properties, or by stiffness (moduli and Poisson ratios, not the density)
max_gap: 0.5            # keep only candidates whose property gap is at most this, or the cell's smallest (0: no bound)
half_shift: true        # also offer every candidate translated by half a cell
void_pair_cost: 0.5     # a pair of faces void on both sides costs this much of a mismatching pair (0..1)
starts: 16              # mismatch descents (random, nearest, random...); the lowest mismatch is kept
max_distance: 0.1       # warn about cells with no candidate this close (normalized units)
tiling: 1               # copies of its structure per cell edge (each cell holds tiling^3 smaller copies)
export:
  voxels: false         # <stem>.voxels.h5, bit-packed, written layer by layer
  stl: false            # <stem>.material<id>.stl per material
  png: false            # <stem>.slices/z00000.png ... one per voxel layer
  stl_max_voxels: 16777216
)";

struct ExportOptions {
  bool voxels = false, stl = false, png = false;
  std::int64_t stl_max_voxels = 0;
};

struct Settings {
  MapperOptions mapper;
  int starts = 16;
  int tiling = 1;
  ExportOptions exports;
};

Settings read_settings(const Config& config) {
  Settings s;
  s.mapper.candidates.k = config.get_or<int>("candidates", 16);
  if (s.mapper.candidates.k < 1 || s.mapper.candidates.k > 4096) config.fail("candidates", "must be 1..4096");
  s.mapper.candidates.stiffness_only = read_stiffness_only(config);
  s.mapper.candidates.max_gap = config.get_or<double>("max_gap", 0.5);
  if (!(s.mapper.candidates.max_gap >= 0)) config.fail("max_gap", "must be >= 0 (0: no bound)");
  if (config.has("radius")) s.mapper.candidates.radius = config.require_positive("radius", "candidate radius");
  s.mapper.half_shift = config.get_or<bool>("half_shift", true);
  s.mapper.void_pair_cost = config.get_or<double>("void_pair_cost", 0.5);
  if (!(s.mapper.void_pair_cost >= 0 && s.mapper.void_pair_cost <= 1))
    config.fail("void_pair_cost", "must lie in [0, 1]");
  s.starts = config.get_or<int>("starts", 16);
  if (s.starts < 1 || s.starts > 1000) config.fail("starts", "must be 1..1000");
  s.mapper.max_distance = config.get_or<double>("max_distance", 0.1);
  if (!(s.mapper.max_distance > 0)) config.fail("max_distance", "must be > 0");
  s.tiling = config.get_or<int>("tiling", 1);
  if (s.tiling < 1 || s.tiling > kMaxTiling) config.fail("tiling", "must be 1.." + std::to_string(kMaxTiling));
  s.exports.voxels = config.get_or<bool>("export.voxels", false);
  s.exports.stl = config.get_or<bool>("export.stl", false);
  s.exports.png = config.get_or<bool>("export.png", false);
  s.exports.stl_max_voxels = config.get_or<std::int64_t>("export.stl_max_voxels", 16777216);
  if (s.exports.stl_max_voxels < 1) config.fail("export.stl_max_voxels", "must be >= 1");
  return s;
}

// "run/part.mapped.h5" -> "run/part"; otherwise drop ".h5".

}  // namespace

int main(int argc, char** argv) {
  StageApp app("msfab-map", "Map a design's cells to microstructures with matching boundaries (thesis 3.5)");
  app.add_common_options();
  app.set_default_config(kDefaults);
  std::string design_path, structures_path;
  app.option("--design", design_path, "msfab.design artifact (the optimized cells)").type_name("FILE").required();
  app.option("--structures", structures_path, "msfab.microstructures artifact of the same space")
      .type_name("FILE")
      .required();
  return app.run(argc, argv, [&](StageContext& ctx) {
    const Settings settings = read_settings(ctx.config);
    ctx.finish_config();
    const std::string out = ctx.require_out();
    ctx.check_out_folder();
    const std::string stem = without_suffix(out, {".mapped.h5", ".h5"});

    const MicrostructureSet set = read_microstructures_artifact(structures_path);
    const Design design = read_design_artifact(design_path);
    check_mapping_inputs(design, design_path, set, structures_path);
    check_set_belongs_to_design(design_path, structures_path);
    ctx.check_memory(mapping_peak_bytes(design, set, settings.mapper),
                     "mapping " + std::to_string(design.cells()) + " cells with " +
                         std::to_string(settings.mapper.candidates.k) + " candidates each",
                     "use fewer candidates");
    const std::int64_t tiles =
        std::int64_t(settings.tiling) * settings.tiling * (design.dimension == 3 ? settings.tiling : 1);
    const std::int64_t model_voxels = design.cells() * set.nx * set.ny * set.nz * tiles;
    if (settings.exports.stl && model_voxels > settings.exports.stl_max_voxels)
      ctx.config.fail("export.stl", "the model has " + std::to_string(model_voxels) +
                                        " voxels, more than export.stl_max_voxels = " +
                                        std::to_string(settings.exports.stl_max_voxels) +
                                        "; raise the limit, or export voxels or png slices instead");
    spdlog::info("{}: {} x {} x {} cells ({}), {}: {} structures of {} x {} x {} voxels", design_path, design.nx,
                 design.ny, design.nz, design.space, structures_path, set.items.size(), set.nx, set.ny, set.nz);
    const auto start = std::chrono::steady_clock::now();

    // 1. Candidates (and their half-shifted variants).
    const CellCandidates candidates = design_candidates(design, set, settings.mapper.candidates);
    // 2. Boundary faces and the mismatch energy of every cell.
    MismatchProblem problem =
        mismatch_problem(design, set, candidates, settings.mapper.half_shift, settings.mapper.void_pair_cost);
    // 3. Greedy descent on the priority list from each start; the lowest
    //    mismatch is kept.
    const MultiStartReport starts = descend_from_starts(problem, ctx.options.seed, settings.starts);
    const DescentReport& descent = starts.kept;
    spdlog::info("final mismatch {} after {} moves ({} cells evaluated), start {} of {}", descent.final, descent.moves,
                 descent.evaluations, starts.kept_start, settings.starts);
    // 4. The mapping artifact.
    MappedDesign mapped = mapped_design(design, set, candidates, problem, descent, settings.mapper);
    mapped.seconds = starts.seconds;
    mapped.tiling = settings.tiling;
    const double mapping_seconds = seconds_since(start);
    write_mapped_artifact(out, mapped, "msfab-map", ctx.config.resolved_text(), {design_path, structures_path},
                          ctx.options.seed);

    const DistanceSummary distances = summarize_distances(candidates, mapped, settings.mapper.max_distance);
    if (distances.far_cells > 0)
      spdlog::warn(
          "{} of {} design cells have no structure within max_distance {} of their target (farthest "
          "nearest candidate {:.4g}); the set does not cover those properties",
          distances.far_cells, distances.design_cells, settings.mapper.max_distance, distances.max_nearest);

    std::int64_t min_cand = 0, max_cand = 0, sum_cand = 0;
    for (std::int64_t c = 0; c < candidates.cells(); ++c) {
      if (design.roles[std::size_t(c)] != CellRole::design) continue;
      const std::int64_t n = candidates.count(c);
      min_cand = sum_cand == 0 ? n : std::min(min_cand, n);
      max_cand = std::max(max_cand, n), sum_cand += n;
    }
    const double mean_cand = distances.design_cells ? double(sum_cand) / double(distances.design_cells) : 0.0;
    std::printf("msfab-map: %lld cells (%d x %d x %d, %lld to map), %.3f s\n", static_cast<long long>(design.cells()),
                design.nx, design.ny, design.nz, static_cast<long long>(distances.design_cells), mapping_seconds);
    if (settings.tiling > 1)
      std::printf("  tiling: %d^%d copies of its structure per cell\n", settings.tiling, design.dimension);
    std::printf("  candidates per cell: %.1f (min %lld, max %lld)%s\n", mean_cand, static_cast<long long>(min_cand),
                static_cast<long long>(max_cand),
                settings.mapper.half_shift ? ", each with its half-shifted exemplar" : "");
    const double drop =
        descent.initial > 0 ? 100.0 * double(descent.initial - descent.final) / double(descent.initial) : 0.0;
    // With a void-pair cost the descent's energy is not the mismatch
    // (MismatchProblem): it is reported as a cost, the mismatch below.
    const bool plain = settings.mapper.void_pair_cost == 0;
    std::printf("  %s: initial %lld, final %lld (-%.1f%%), %lld moves, %lld evaluations, descent %.3f s\n",
                plain ? "mismatch" : "cost (16 mismatch + 16 c void pairs)", static_cast<long long>(descent.initial),
                static_cast<long long>(descent.final), drop, static_cast<long long>(descent.moves),
                static_cast<long long>(descent.evaluations), starts.seconds);
    const double face_pairs = double(mapped.mismatch_pairs + mapped.void_pairs + mapped.contact_pairs);
    if (face_pairs > 0)
      std::printf(
          "  voxel pairs across cell faces: %.1f%% solid on both sides, %.1f%% differing, %.1f%% void on both\n",
          100 * double(mapped.contact_pairs) / face_pairs, 100 * double(mapped.mismatch_pairs) / face_pairs,
          100 * double(mapped.void_pairs) / face_pairs);
    if (settings.starts > 1) {
      std::string finals;
      for (std::int64_t f : starts.finals) finals += (finals.empty() ? "" : ", ") + std::to_string(f);
      std::printf("  starts: %d (final %s %s), kept start %d\n", settings.starts, plain ? "mismatch" : "cost",
                  finals.c_str(), starts.kept_start);
    }
    std::printf("  distance to target: max %.4g (nearest candidate: max %.4g; %lld cells beyond max_distance %g)\n",
                distances.max_chosen, distances.max_nearest, static_cast<long long>(distances.far_cells),
                settings.mapper.max_distance);
    std::printf("  property gap |C(structure) - C(target)| / |C(target)|: max %.4g, mean %.4g\n", distances.max_gap,
                distances.mean_gap);
    // The mass the structures bring against the design's (the density is
    // the space's last property).
    double design_rho = 0, mapped_rho = 0;
    for (std::int64_t c = 0; c < design.cells(); ++c) {
      if (mapped.structure[std::size_t(c)] < 0) continue;
      const Microstructure& m = set.items[std::size_t(mapped.structure[std::size_t(c)])];
      design_rho += design.raw(c, design.raw.cols() - 1);
      mapped_rho += m.properties[m.properties.size() - 1];
    }
    if (design_rho > 0)
      std::printf("  material in the mapped cells: %+.1f%% against the design's (match: %s)\n",
                  100.0 * (mapped_rho / design_rho - 1),
                  settings.mapper.candidates.stiffness_only ? "stiffness" : "all");
    std::printf("  artifact: %s\n", out.c_str());

    // Exports of the voxel model, each streamed layer by layer.
    if (!settings.exports.voxels && !settings.exports.stl && !settings.exports.png) return;
    const VoxelModel model(mapped, set);
    const auto export_start = std::chrono::steady_clock::now();
    if (settings.exports.voxels) {
      const std::string path = stem + ".voxels.h5";
      write_voxels_artifact(path, model, "msfab-map", ctx.config.resolved_text(), {design_path, structures_path},
                            ctx.options.seed);
      std::printf("  voxels: %s (%lld x %lld x %lld)\n", path.c_str(), static_cast<long long>(model.nx()),
                  static_cast<long long>(model.ny()), static_cast<long long>(model.nz()));
    }
    if (settings.exports.stl) {
      const StlExport stl = write_material_stls(stem, model);
      for (std::size_t i = 0; i < stl.paths.size(); ++i)
        std::printf("  stl: %s (%lld triangles)\n", stl.paths[i].c_str(), static_cast<long long>(stl.triangles[i]));
    }
    if (settings.exports.png) {
      const std::int64_t n = write_png_slices(stem + ".slices", model);
      std::printf("  png: %s.slices/ (%lld layers)\n", stem.c_str(), static_cast<long long>(n));
    }
    std::printf("  exports: %.3f s\n", seconds_since(export_start));
  });
}
