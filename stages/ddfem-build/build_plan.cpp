#include "build_plan.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <limits>

#include "core/errors.hpp"
#include "ddfem/cube_symmetry.hpp"
#include "ddfem/level2_block.hpp"

namespace msfab {
namespace {

// FNV-1a of the file's bytes: a resumed level-2 build must see the same base.
std::string file_fingerprint(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::uint64_t h = 1469598103934665603ULL;
  for (std::istreambuf_iterator<char> it(in), end; it != end; ++it)
    h = (h ^ static_cast<unsigned char>(*it)) * 1099511628211ULL;
  char text[32];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
  return text;
}

// Layers of periodic copies the blocks are built with (patch sampling only).
int patch_context(const BuildOptions& options) {
  const ForceSamplingOptions& s = options.fit.sampling;
  return s.mode == ForceSamplingOptions::Mode::patch ? s.context : 0;
}

}  // namespace

BuildPlan plan_level1(const BuildOptions& options) {
  BuildPlan plan;
  plan.db.level = 1;
  plan.db.materials = options.materials;
  plan.db.void_children = options.void_children;
  const std::int64_t N = plan.db.num_combinations();
  plan.item_of.assign(N, -1);
  for (std::int64_t code = 0; code < N; ++code) {
    if (is_all_void(plan.db.combination_ids(code))) continue;  // no element, nothing to fit
    const std::int64_t rep =
        options.use_symmetry ? plan.db.combination_code(canonical_block(plan.db.combination_ids(code)).ids) : code;
    plan.item_of[code] = rep;
    if (rep == code) plan.items.push_back(code);
  }
  plan.db.num_orbits = static_cast<int>(plan.items.size());
  plan.points = 8;
  const auto palette = plan.db.palette();
  CoarseDatabase codes;  // only the palette size and void_children matter for decoding
  codes.materials = plan.db.materials;
  codes.void_children = plan.db.void_children;
  plan.block = [palette, codes, h = options.voxel_size, context = patch_context(options)](std::int64_t code) {
    return make_fine_block(codes.combination_ids(code), palette, h, 2, context);
  };
  plan.void_children = [codes](std::int64_t code) {
    const BlockMaterials ids = codes.combination_ids(code);
    return static_cast<int>(std::count(ids.begin(), ids.end(), 0));
  };
  return plan;
}

BuildPlan plan_level2(const BuildOptions& options, const MemoryCheck& check_memory) {
  auto base = std::make_shared<CoarseDatabase>(read_coarse_db(options.base_database));
  if (base->level != 1)
    throw InputError(options.base_database + ": base_database must be a level-1 database, this one is level " +
                     std::to_string(base->level));
  for (const CoarseMaterialFit& fit : base->entries)
    if (!fit.fitted)
      throw InputError(options.base_database +
                       ": holds blocks that were not fitted (the all-void block, or blocks "
                       "with void children without usable samples); compress it first with msfab-ddfem-compress, "
                       "which keeps the fitted ones");
  const int k1 = static_cast<int>(base->entries.size());
  // The first pairing stage holds every one of the (k1 + 1)^2 candidates'
  // log-energy features (8 B each) and the farthest-point search's distance
  // and nearest representative (12 B); the later stages pair at most
  // max(representatives)^2. The thesis paired all 6561 level-1 materials of
  // its palette: 43 M candidates, about 11.5 GB with 32 deformations.
  const double pairs = std::pow(std::max<double>(k1 + 1, *std::max_element(options.hierarchy.representatives.begin(),
                                                                           options.hierarchy.representatives.end())),
                                2.0);
  check_memory(pairs * (8.0 * options.hierarchy.features() + 12.0),
               "pairing " + std::to_string(k1) + " level-1 materials (" + std::to_string(std::int64_t(k1) * k1) +
                   " candidates x " + std::to_string(options.hierarchy.deformations) + " level2.deformations)",
               "compress the base first (msfab-ddfem-compress --set representatives=K)");
  if (std::int64_t(k1 + 1) * (k1 + 1) > std::numeric_limits<int>::max())
    throw InputError(options.base_database + ": " + std::to_string(k1) +
                     " coarse materials give more pair candidates than a lookup table can index; compress it first");
  BuildPlan plan;
  plan.db.level = 2;
  plan.db.materials = base->materials;
  plan.db.num_orbits = base->num_orbits;
  plan.db.level1 = base;
  // Over a database with void children, the all-void level-1 child is one
  // more input of the hierarchy; its level-2 blocks are sampled among
  // periodic copies, as at level 1.
  const bool void_input = base->void_children;
  if (void_input && options.fit.sampling.mode != ForceSamplingOptions::Mode::periodic)
    throw InputError(options.base_database + ": has void children; its level-2 blocks need sampling.mode: periodic");
  const auto t0 = std::chrono::steady_clock::now();
  plan.db.hierarchy = build_level2_hierarchy(base->entries, 2 * options.voxel_size, options.hierarchy, void_input);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  int inputs = k1;
  for (int s = 0; s < 3; ++s) {
    const PairStage& stage = plan.db.hierarchy.stages[s];
    spdlog::info(
        "level 2, pairs along {}: {} candidates -> {} representatives (Eq. 2.10 distance mean {:.4f}, max {:.4f})",
        "xyz"[s], std::int64_t(inputs) * inputs, stage.outputs(), stage.mean_distance, stage.max_distance);
    inputs = stage.outputs();
  }
  spdlog::info("level 2 hierarchy: {:.2f} s", seconds);
  for (int r = 0; r < plan.db.hierarchy.num_final(); ++r) plan.items.push_back(r);
  plan.points = 64;
  plan.fingerprint = "base_database " + file_fingerprint(options.base_database);
  if (options.level2_voxel_samples) plan.fingerprint += " samples voxels";
  plan.block = [base, palette = base->palette(), hierarchy = plan.db.hierarchy, h = options.voxel_size,
                context = patch_context(options), voxels = options.level2_voxel_samples](std::int64_t r) {
    const Arrangement arr = hierarchy.arrangement(2, static_cast<int>(r));
    std::array<const CoarseMaterialFit*, 8> children;
    BlockMaterials ids;
    for (int c = 0; c < 8; ++c) {
      const bool is_void = arr[c] == hierarchy.void_entry();
      children[c] = is_void ? nullptr : &base->entries[arr[c]];
      ids[c] = is_void ? 0 : arr[c] + 1;
    }
    if (voxels) return make_voxel_block(level2_voxel_ids(children), palette, h, ids);
    return make_block_of_coarse_materials(children, ids, 2 * h, context);
  };
  plan.void_children = [hierarchy = plan.db.hierarchy](std::int64_t r) {
    const Arrangement arr = hierarchy.arrangement(2, static_cast<int>(r));
    return static_cast<int>(std::count(arr.begin(), arr.end(), hierarchy.void_entry()));
  };
  return plan;
}

CoarseDatabase assemble_database(BuildPlan plan, const FittedOrbits& done) {
  CoarseDatabase& db = plan.db;
  // A block with a void child may have no fit (every sample a mechanism,
  // e.g. children that touch only along an edge); online it is coarsened
  // naively, as in a database without void children. Any other block must fit.
  int unfitted = 0, unfitted_void = 0;
  for (const auto& [item, fit] : done) {
    if (fit.fitted) continue;
    const int void_children = plan.void_children(item);
    if (void_children == 8) continue;  // no element
    if (void_children > 0) {
      ++unfitted_void;
      spdlog::debug("block {} {} not fitted ({}); coarsened naively online", item, block_name(fit.material_ids),
                    fit.not_fitted_reason);
    } else {
      ++unfitted;
      spdlog::error("block {} {} could not be fitted: {}", item, block_name(fit.material_ids), fit.not_fitted_reason);
    }
  }
  if (unfitted > 0) throw NumericalError(std::to_string(unfitted) + " block(s) could not be fitted");
  if (unfitted_void > 0)
    spdlog::warn(
        "{} of {} fitted blocks with void children have no fit (no usable samples); they are coarsened naively",
        unfitted_void, done.size());
  if (db.level == 2) {
    for (std::int64_t r : plan.items) db.entries.push_back(done.at(r));
    return db;
  }
  // Level 1: every combination from its orbit's representative.
  const auto& symmetries = cube_symmetries();
  const std::int64_t N = db.num_combinations();
  db.entries.resize(N);
  db.entry_of.resize(N);
  db.orbit.resize(N);
  for (std::int64_t c = 0; c < N; ++c) {
    const std::int64_t rep = plan.item_of[c];
    if (rep < 0) {  // the all-void combination: no element
      db.orbit[c] = -1;
      db.entry_of[c] = -1;
      db.entries[c].material_ids = db.combination_ids(c);
      continue;
    }
    db.orbit[c] = static_cast<int>(rep);
    db.entry_of[c] = static_cast<int>(c);
    const CoarseMaterialFit& image = done.at(rep);
    if (rep == c) {
      db.entries[c] = image;
    } else {
      const BlockMaterials ids = db.combination_ids(c);
      db.entries[c] = map_fit_back(symmetries[canonical_block(ids).symmetry], image, ids);
    }
  }
  return db;
}

}  // namespace msfab
