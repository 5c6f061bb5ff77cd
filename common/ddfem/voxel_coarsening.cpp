#include "ddfem/voxel_coarsening.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <set>

#include "core/errors.hpp"
#include "ddfem/baseline_coarsening.hpp"
#include "ddfem/matched_coarsening.hpp"

namespace msfab {

namespace {

// The database's lookup, except where a solid mixed block's fit has a
// response to uniform strains farther than `tolerance` from the block's own
// C^H: there the matched model, which has that C^H by construction. The fit
// comes from a representative (compression, the level-2 pairing stages), so
// its stiffness can sit elsewhere in the block than the block's own; C^H is
// computed from the block itself.
CoarseMaterialLookup checked_lookup(const CoarseDatabase& db, const std::vector<MaterialPtr>& palette,
                                    const CoarseGrid& level1, int level, double tolerance, bool enhanced,
                                    CoarseMaterialLookup database, CoarsenedVoxels* counts) {
  return [&db, palette, combos = level1.combinations, level, tolerance, enhanced, database,
          counts](const ChildIds& ids) {
    const CoarseMaterialFit* fit = level == 2 ? find_level2_fit(db, combos, ids) : db.find(ids);
    if (!fit) return database(ids);
    const std::vector<int> voxels = level == 2 ? block_level2(ids, combos) : block_level1(ids);
    const bool solid = std::find(voxels.begin(), voxels.end(), 0) == voxels.end();
    const bool mixed = std::any_of(voxels.begin(), voxels.end(), [&](int id) { return id != voxels[0]; });
    if (!solid || !mixed) return database(ids);
    if (counts) ++counts->checked_blocks;
    const int n = level == 2 ? 4 : 2;
    const Mat6 CH = block_homogenized_stiffness(palette, voxels, n);
    if (stiffness_distance(fit_uniform_response(*fit), CH) <= tolerance) return database(ids);
    if (counts) ++counts->replaced_blocks;
    return matched_block_materials(palette, voxels, n, enhanced, &CH);
  };
}

// The coarse mesh of `cells` (one combination per cell) with windowed
// matched materials. The cells are independent (one homogenization each),
// so they are computed in parallel; each result depends on its cell alone,
// not on the threads.
VoxelMesh windowed_matched_mesh(const VoxelGrid& fine, const std::vector<MaterialPtr>& palette,
                                const CoarseGrid& cells, const CoarseGrid* level1, bool enhanced, int margin,
                                CoarseMeshStats* stats, int* unresolved_windows) {
  std::vector<int> cell_of;  // combination k is the k-th solid cell
  for (int c = 0; c < cells.num_cells(); ++c)
    if (cells.cell_combination[c] >= 0) cell_of.push_back(c);
  const int count = static_cast<int>(cell_of.size());
  std::vector<char> unresolved(count, 0);
  std::vector<QuadratureMaterials> per_cell(count);
  std::exception_ptr failure;
#pragma omp parallel for schedule(dynamic)
  for (int k = 0; k < count; ++k) {
    try {
      bool u = false;
      per_cell[k] = windowed_matched_cell(fine, palette, cells, level1, enhanced, margin, cell_of[k], &u);
      unresolved[k] = u;
    } catch (...) {
#pragma omp critical(windowed_failure)
      if (!failure) failure = std::current_exception();
    }
  }
  if (failure) std::rethrow_exception(failure);
  *unresolved_windows = static_cast<int>(std::count(unresolved.begin(), unresolved.end(), 1));
  return build_coarse_mesh(cells, IndexedMaterialLookup([&per_cell](int c) { return per_cell[c]; }), 0, stats, enhanced);
}

}  // namespace

CoarseMaterialLookup baseline_coarsening(const std::string& name, const std::vector<MaterialPtr>& palette,
                                         const CoarseGrid* level1, bool enhanced) {
  if (name == "naive") return level1 ? naive_coarsening(palette, *level1) : naive_coarsening(palette);
  if (name == "averaged") return level1 ? averaged_coarsening(palette, *level1) : averaged_coarsening(palette);
  if (name == "galerkin") return level1 ? galerkin_coarsening(palette, *level1) : galerkin_coarsening(palette);
  if (name == "homogenized") return level1 ? homogenized_coarsening(palette, *level1) : homogenized_coarsening(palette);
  if (name == "matched") return level1 ? matched_coarsening(palette, *level1, enhanced) : matched_coarsening(palette, enhanced);
  throw InputError("coarse materials: expected naive, averaged, galerkin, homogenized or matched, got '" + name + "'");
}

CoarseMaterialLookup ddfem_lookup(const CoarseDatabase& db, const std::vector<MaterialPtr>& palette,
                                  const CoarseGrid& level1, int level, const CoarsenedVoxels& settings,
                                  CoarsenedVoxels* counts) {
  // Blocks the database holds no fit for (void children in a database built
  // without them, blocks that could not be fitted) go to the fallback.
  const bool enhanced = settings.element == "enhanced";
  const CoarseMaterialLookup fallback =
      baseline_coarsening(settings.fallback, palette, level == 2 ? &level1 : nullptr, enhanced);
  const CoarseMaterialLookup counted = [fallback, counts](const ChildIds& ids) {
    if (counts) ++counts->fallback_blocks;
    return fallback(ids);
  };
  const CoarseMaterialLookup lookup =
      level == 2 ? database_coarsening_level2(db, level1, counted) : database_coarsening(db, counted);
  if (!(settings.check_tolerance > 0)) return lookup;
  return checked_lookup(db, palette, level1, level, settings.check_tolerance, enhanced, lookup, counts);
}

CoarsenedVoxels coarsen_voxels(const VoxelGrid& grid, const std::vector<MaterialPtr>& palette,
                               const CoarseningRequest& request) {
  if (request.fallback != "naive" && request.fallback != "galerkin" && request.fallback != "matched")
    throw InputError("--coarse-fallback: expected naive, galerkin or matched, got '" + request.fallback + "'");
  if (request.level < 1 || request.level > 2)
    throw InputError("--coarsen: level must be 0, 1 or 2, got " + std::to_string(request.level));
  if (request.material != "ddfem" && request.material != "naive" && request.material != "averaged" &&
      request.material != "homogenized" && request.material != "galerkin" && request.material != "matched")
    throw InputError("--coarse-material: expected ddfem, naive, averaged, homogenized, galerkin or matched, got '" +
                     request.material + "'");
  if (!(request.check_tolerance >= 0) || !std::isfinite(request.check_tolerance))
    throw InputError("--coarse-check: the tolerance must be >= 0 and finite (0: no check)");
  if (request.check_tolerance > 0 && request.material != "ddfem")
    throw InputError("--coarse-check: applies to --coarse-material ddfem only (got " + request.material + ")");
  if (request.window < 0) throw InputError("--coarse-window: the margin must be >= 0 voxels (0: off)");
  if (request.window > 0 && request.material != "matched")
    throw InputError("--coarse-window: applies to --coarse-material matched only (got " + request.material + ")");
  if (request.fallback != "naive" && request.material != "ddfem")
    throw InputError("--coarse-fallback " + request.fallback + ": applies to --coarse-material ddfem only (got " +
                     request.material + ")");
  CoarsenedVoxels m;
  if (request.material == "ddfem") {
    if (request.database.empty())
      throw InputError("--coarse-material ddfem needs --database (a coarse_db from msfab-ddfem-build)");
    m.database = std::make_shared<CoarseDatabase>(read_coarse_db(request.database));
    if (request.level != m.database->level)
      throw InputError(request.database + ": a level-" + std::to_string(m.database->level) +
                       " database cannot coarsen to level " + std::to_string(request.level));
    std::set<int> used(grid.ids.begin(), grid.ids.end());
    check_scene_palette(*m.database, request.database, palette, std::vector<int>(used.begin(), used.end()));
    // A fit is only right on the element it was fitted for.
    const std::string fitted_for = m.database->enhanced_element() ? "enhanced" : "trilinear";
    if (!request.element.empty() && request.element != fitted_for)
      throw InputError(request.database + ": fitted for the " + fitted_for + " coarse element; --coarse-element " +
                       request.element + " would put its materials on another element");
    m.element = fitted_for;
    if (request.check_tolerance > 0 && fitted_for != "enhanced")
      throw InputError("--coarse-check: " + request.database +
                       " was fitted for the trilinear element, whose fits soften their response to uniform "
                       "strains on purpose to offset its bending locking; the check compares that response "
                       "with the block's C^H and needs a database fitted for the enhanced element "
                       "(fit.element: enhanced)");
  }
  if (!request.element.empty()) m.element = request.element;
  const auto t0 = std::chrono::steady_clock::now();
  m.level1 = coarsen_grid(grid);
  m.grid = request.level == 2 ? coarsen_grid(m.level1) : m.level1;
  const CoarseGrid* level1 = request.level == 2 ? &m.level1 : nullptr;
  if (request.window > 0) {
    m.grid = with_one_combination_per_cell(m.grid);
    m.mesh = windowed_matched_mesh(grid, palette, m.grid, level1, m.element == "enhanced", request.window, &m.stats,
                                   &m.unresolved_windows);
  } else {
    CoarseMaterialLookup lookup;
    if (request.material != "ddfem") {
      lookup = baseline_coarsening(request.material, palette, level1, m.element == "enhanced");
    } else {
      m.fallback = request.fallback;
      m.check_tolerance = request.check_tolerance;
      lookup = ddfem_lookup(*m.database, palette, m.level1, request.level, m, &m);
    }
    m.mesh = build_coarse_mesh(m.grid, lookup, 0, &m.stats, m.element == "enhanced");
  }
  m.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return m;
}

}  // namespace msfab
