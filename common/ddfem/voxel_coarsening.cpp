#include "ddfem/voxel_coarsening.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <functional>
#include <map>
#include <set>

#include "core/errors.hpp"
#include "ddfem/baseline_coarsening.hpp"
#include "ddfem/matched_coarsening.hpp"
#include "ddfem/windowed_stiffness.hpp"

namespace msfab {

namespace {

// The database's fit for a block, or null (level 1: child ids are fine ids;
// level 2: indices + 1 into the level-1 grid's `combinations`).
const CoarseMaterialFit* database_fit(const CoarseDatabase& db, const std::vector<ChildIds>& combinations, int level,
                                      const ChildIds& ids) {
  return level == 2 ? find_level2_fit(db, combinations, ids) : db.find(ids);
}

// What deciding one cell's (or block's) materials found. Per cell, so that
// cells can be decided in parallel and counted afterwards.
struct CellOutcome {
  bool unresolved = false;  // the window gave no stiffness: the cell's own C^H was used
  bool checked = false;     // a solid mixed cell whose fit was checked
  bool replaced = false;    // ... and coarsened by the matched model instead
};

// The stiffness a solid mixed block's fit is checked against, from the
// block's voxels (laid out as block_level1 / block_level2 give them).
using ReferenceStiffness = std::function<Mat6(const std::vector<int>& voxels, CellOutcome& outcome)>;

// The database's lookup, except where a solid mixed block's fit has a
// response to uniform strains farther than `tolerance` from the block's
// reference stiffness: there the matched model, which has that stiffness by
// construction. The fit comes from a representative (compression, the
// level-2 pairing stages), so its stiffness can sit elsewhere in the block
// than the block's own. The reference is the block's own periodic C^H, or
// (`reference`) the cell's stiffness among its neighbours.
QuadratureMaterials checked_block(const CoarseDatabase& db, const std::vector<MaterialPtr>& palette,
                                  const std::vector<ChildIds>& combos, int level, double tolerance, bool enhanced,
                                  const CoarseMaterialLookup& database, const ChildIds& ids, CellOutcome& outcome,
                                  const ReferenceStiffness& reference = nullptr) {
  const CoarseMaterialFit* fit = database_fit(db, combos, level, ids);
  if (!fit) return database(ids);
  const std::vector<int> voxels = level == 2 ? block_level2(ids, combos) : block_level1(ids);
  if (!solid_mixed_block(voxels)) return database(ids);
  outcome.checked = true;
  const int n = level == 2 ? 4 : 2;
  const Mat6 C = reference ? reference(voxels, outcome) : block_homogenized_stiffness(palette, voxels, n);
  if (stiffness_distance(fit_uniform_response(*fit), C) <= tolerance) return database(ids);
  outcome.replaced = true;
  return matched_block_materials(palette, voxels, n, enhanced, &C);
}

// materials[k] = decide(k, outcome[k]) for k < count, in parallel: each
// result depends on its k alone, not on the threads. A failure is rethrown
// after the loop, the one of the smallest k whatever the threads.
std::vector<QuadratureMaterials> decide_in_parallel(
    int count, std::vector<CellOutcome>& outcome,
    const std::function<QuadratureMaterials(int k, CellOutcome& outcome)>& decide) {
  outcome.assign(count, CellOutcome{});
  std::vector<QuadratureMaterials> materials(count);
  std::vector<std::exception_ptr> failure(count);
#pragma omp parallel for schedule(dynamic)
  for (int k = 0; k < count; ++k) {
    try {
      materials[k] = decide(k, outcome[k]);
    } catch (...) {
      failure[k] = std::current_exception();
    }
  }
  for (const std::exception_ptr& f : failure)
    if (f) std::rethrow_exception(f);
  return materials;
}

CoarseMaterialLookup checked_lookup(const CoarseDatabase& db, const std::vector<MaterialPtr>& palette,
                                    const CoarseGrid& level1, int level, double tolerance, bool enhanced,
                                    CoarseMaterialLookup database, CoarsenedVoxels* counts) {
  return
      [&db, palette, combos = level1.combinations, level, tolerance, enhanced, database, counts](const ChildIds& ids) {
        CellOutcome outcome;
        QuadratureMaterials m = checked_block(db, palette, combos, level, tolerance, enhanced, database, ids, outcome);
        if (counts) {
          counts->checked_blocks += outcome.checked;
          counts->replaced_blocks += outcome.replaced;
        }
        return m;
      };
}

// The checked lookup's materials for every distinct block of `grid`, in
// parallel: each block's materials depend on the block alone (its periodic
// homogenization and matched model are most of a checked coarsening's
// time). `database` must be safe to call from several threads (the plain
// database lookup and its fallbacks are). Counts are summed per block.
std::vector<QuadratureMaterials> checked_blocks_in_parallel(
    const CoarseDatabase& db, const std::vector<MaterialPtr>& palette, const CoarseGrid& level1, const CoarseGrid& grid,
    int level, double tolerance, bool enhanced, const CoarseMaterialLookup& database, CoarsenedVoxels& counts) {
  std::vector<CellOutcome> outcome;
  std::vector<QuadratureMaterials> materials =
      decide_in_parallel(static_cast<int>(grid.combinations.size()), outcome, [&](int c, CellOutcome& o) {
        return checked_block(db, palette, level1.combinations, level, tolerance, enhanced, database,
                             grid.combinations[c], o);
      });
  for (const CellOutcome& o : outcome) {
    counts.checked_blocks += o.checked;
    counts.replaced_blocks += o.replaced;
  }
  return materials;
}

using CellMaterials = std::function<QuadratureMaterials(int cell, CellOutcome& outcome)>;

// The coarse mesh of `cells` (one combination per solid cell, as
// with_one_combination_per_cell numbers them) with each cell's materials
// from `materials`, which depend on the cell's window of `margin` voxels of
// `fine` alone. So cells with equal windows (a laminate's, a repeated
// pattern's) are decided once, by the first of them in cell order, and the
// distinct windows in parallel: each result depends on its window alone,
// not on the threads. The outcomes are summed into `counts` per cell.
VoxelMesh per_cell_mesh(const VoxelGrid& fine, const CoarseGrid& cells, int margin, const CellMaterials& materials,
                        bool enhanced, CoarseMeshStats* stats, CoarsenedVoxels* counts) {
  const int n = cells.fine_per_cell();
  std::vector<int> window_of;   // the k-th solid cell (combination k) has the window_of[k]-th distinct window
  std::vector<int> first_cell;  // the first solid cell of each distinct window
  {
    // The windows themselves ((n + 2 margin)^3 ids each) are needed only to
    // find the distinct ones.
    std::map<std::vector<int>, int> distinct;
    for (int c = 0; c < cells.num_cells(); ++c) {
      if (cells.cell_combination[c] < 0) continue;
      const std::array<int, 3> v = cells.first_voxel(c);
      const auto [it, added] =
          distinct.emplace(cell_window(fine, v[0], v[1], v[2], n, margin), static_cast<int>(first_cell.size()));
      if (added) first_cell.push_back(c);
      window_of.push_back(it->second);
    }
  }
  const int count = static_cast<int>(first_cell.size());
  std::vector<CellOutcome> outcome;
  const std::vector<QuadratureMaterials> per_window =
      decide_in_parallel(count, outcome, [&](int k, CellOutcome& o) { return materials(first_cell[k], o); });
  for (int w : window_of) {
    counts->unresolved_windows += outcome[w].unresolved;
    counts->checked_blocks += outcome[w].checked;
    counts->replaced_blocks += outcome[w].replaced;
  }
  counts->distinct_windows = count;
  return build_coarse_mesh(cells, IndexedMaterialLookup([&](int k) { return per_window[window_of[k]]; }), 0, stats,
                           enhanced);
}

// The windowed check of one cell (`--coarse-check TAU --coarse-window M`):
// the checked lookup with the cell's stiffness among its real neighbours in
// place of its periodic C^H, so that a fit is kept only where it responds
// like the cell in this scene, and otherwise replaced by the matched model
// carried onto that stiffness (the windowed matched materials).
QuadratureMaterials windowed_checked_cell(const VoxelGrid& fine, const std::vector<MaterialPtr>& palette,
                                          const CoarseDatabase& db, const CoarseGrid& level1, int level,
                                          const CoarseGrid& cells, const CoarseMaterialLookup& lookup, bool enhanced,
                                          int margin, double tolerance, int cell, CellOutcome& outcome) {
  return checked_block(db, palette, level1.combinations, level, tolerance, enhanced, lookup,
                       cells.combinations[cells.cell_combination[cell]], outcome,
                       [&](const std::vector<int>& voxels, CellOutcome& o) {
                         return cell_windowed_stiffness(fine, palette, cells, voxels, cell, margin, &o.unresolved);
                       });
}

}  // namespace

CoarseMaterialLookup baseline_coarsening(const std::string& name, const std::vector<MaterialPtr>& palette,
                                         const CoarseGrid* level1, bool enhanced) {
  if (name == "naive") return level1 ? naive_coarsening(palette, *level1) : naive_coarsening(palette);
  if (name == "averaged") return level1 ? averaged_coarsening(palette, *level1) : averaged_coarsening(palette);
  if (name == "galerkin" || name == "galerkin-full") {
    const bool reduced = name == "galerkin";
    return level1 ? galerkin_coarsening(palette, *level1, reduced) : galerkin_coarsening(palette, reduced);
  }
  if (name == "homogenized") return level1 ? homogenized_coarsening(palette, *level1) : homogenized_coarsening(palette);
  if (name == "matched")
    return level1 ? matched_coarsening(palette, *level1, enhanced) : matched_coarsening(palette, enhanced);
  throw InputError(
      "coarse materials: expected naive, averaged, galerkin, galerkin-full, homogenized or matched, got '" + name +
      "'");
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

namespace {

// The checked coarsenings' plain database lookup (the check is theirs to
// make, per block or per cell, in parallel), with the run's fallback and
// tolerance recorded in `m` and the blocks without a fit counted once per
// distinct block (the lookup itself counts nothing: it runs on several
// threads).
CoarseMaterialLookup unchecked_lookup_for_the_check(CoarsenedVoxels& m, const std::vector<MaterialPtr>& palette,
                                                    const CoarseningRequest& request) {
  m.fallback = request.fallback;
  m.check_tolerance = request.check_tolerance;
  for (const ChildIds& c : m.grid.combinations)
    m.fallback_blocks += !database_fit(*m.database, m.level1.combinations, request.level, c);
  CoarsenedVoxels unchecked = m;
  unchecked.check_tolerance = 0;
  return ddfem_lookup(*m.database, palette, m.level1, request.level, unchecked, nullptr);
}

}  // namespace

CoarsenedVoxels coarsen_voxels(const VoxelGrid& grid, const std::vector<MaterialPtr>& palette,
                               const CoarseningRequest& request) {
  if (request.fallback != "naive" && request.fallback != "galerkin" && request.fallback != "galerkin-full" &&
      request.fallback != "matched")
    throw InputError("--coarse-fallback: expected naive, galerkin, galerkin-full or matched, got '" + request.fallback +
                     "'");
  if (request.level < 1 || request.level > 2)
    throw InputError("--coarsen: level must be 0, 1 or 2, got " + std::to_string(request.level));
  if (request.material != "ddfem" && request.material != "naive" && request.material != "averaged" &&
      request.material != "homogenized" && request.material != "galerkin" && request.material != "galerkin-full" &&
      request.material != "matched")
    throw InputError(
        "--coarse-material: expected ddfem, naive, averaged, homogenized, galerkin, galerkin-full or matched, got '" +
        request.material + "'");
  if (!(request.check_tolerance >= 0) || !std::isfinite(request.check_tolerance))
    throw InputError("--coarse-check: the tolerance must be >= 0 and finite (0: no check)");
  if (request.check_tolerance > 0 && request.material != "ddfem")
    throw InputError("--coarse-check: applies to --coarse-material ddfem only (got " + request.material + ")");
  if (request.window < 0) throw InputError("--coarse-window: the margin must be >= 0 voxels (0: off)");
  if (request.window > 0 && request.material != "matched" &&
      !(request.material == "ddfem" && request.check_tolerance > 0))
    throw InputError("--coarse-window: applies to --coarse-material matched, or ddfem with --coarse-check (got " +
                     request.material + (request.material == "ddfem" ? " without --coarse-check)" : ")"));
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
  if (request.window > 0 && request.material == "matched") {
    const CoarseGrid cells = with_one_combination_per_cell(m.grid);
    const bool enhanced = m.element == "enhanced";
    m.mesh = per_cell_mesh(
        grid, cells, request.window,
        [&](int cell, CellOutcome& o) {
          return windowed_matched_cell(grid, palette, cells, level1, enhanced, request.window, cell, &o.unresolved);
        },
        enhanced, &m.stats, &m);
    m.grid = cells;
  } else if (request.window > 0) {  // ddfem, checked against each cell's windowed stiffness
    const CoarseMaterialLookup lookup = unchecked_lookup_for_the_check(m, palette, request);
    const CoarseGrid cells = with_one_combination_per_cell(m.grid);
    const bool enhanced = m.element == "enhanced";
    m.mesh = per_cell_mesh(
        grid, cells, request.window,
        [&](int cell, CellOutcome& o) {
          return windowed_checked_cell(grid, palette, *m.database, m.level1, request.level, cells, lookup, enhanced,
                                       request.window, request.check_tolerance, cell, o);
        },
        enhanced, &m.stats, &m);
    m.grid = cells;
  } else if (request.material == "ddfem" && request.check_tolerance > 0) {
    const CoarseMaterialLookup lookup = unchecked_lookup_for_the_check(m, palette, request);
    const std::vector<QuadratureMaterials> materials =
        checked_blocks_in_parallel(*m.database, palette, m.level1, m.grid, request.level, request.check_tolerance,
                                   m.element == "enhanced", lookup, m);
    m.mesh = build_coarse_mesh(m.grid, IndexedMaterialLookup([&](int c) { return materials[c]; }), 0, &m.stats,
                               m.element == "enhanced");
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
