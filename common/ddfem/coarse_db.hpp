#pragma once
// The DDFEM coarse-material database (thesis §2.3): for every combination of
// solid palette materials in a 2 x 2 x 2 block, the fitted coarse material
// of Eq. 2.7, stored in the `msfab.coarse_db` artifact (docs/artifacts.md).
//
// Combinations are keyed by the block's eight palette ids in hex8 child
// order (level 1; level 2 goes through the hierarchy of hierarchy.hpp). A
// database built without void children stores the n^8 all-solid
// combinations, and a block with a void child is coarsened naively online;
// one built with them (`void_children`, periodic sampling) stores the
// (n + 1)^8 - 1 combinations with at least one solid child (docs/ddfem.md,
// "Blocks with void").
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "ddfem/coarse_fit.hpp"
#include "ddfem/coarse_grid.hpp"
#include "ddfem/hierarchy.hpp"

namespace msfab {

constexpr const char* kCoarseDbSchema = "msfab.coarse_db";
constexpr int kCoarseDbSchemaVersion = 1;

// One solid palette material (Neo-Hookean); palette id = index + 1, id 0 is void.
struct DbMaterial {
  std::string name;
  double E = 0, nu = 0, density = 0;
};

struct CoarseDatabase {
  int level = 1;
  std::vector<DbMaterial> materials;  // ids 1..n
  // Combinations include void children (id 0): codes in base n + 1, the
  // all-void code 0 has no entry. Otherwise base n over the solid ids.
  bool void_children = false;
  // The stored coarse materials: one per combination in a full database,
  // the representatives in a compressed one (msfab-ddfem-compress).
  std::vector<CoarseMaterialFit> entries;
  // Per combination code: the index of its entry (its own, or its
  // representative's), -1 if none.
  std::vector<int> entry_of;
  std::vector<int> orbit;  // per combination code: code of its symmetry orbit's representative
  int num_orbits = 0;
  // Level 2 only (§2.3.5): the level-1 database whose coarse materials are
  // this level's palette, and the pairing stages that look the level-1
  // entries of a cell's 8 children up to a row of `entries` (the 64-point
  // fit of hierarchy.arrangement(2, row)). A level-2 fit's material_ids are
  // its children's level-1 entries + 1. `entry_of` and `orbit` stay empty.
  std::shared_ptr<const CoarseDatabase> level1;
  Level2Hierarchy hierarchy;

  int num_materials() const { return static_cast<int>(materials.size()); }
  // Whether the stored fits are for the coarse element with bubble modes
  // (the online coarse mesh must use that element).
  bool enhanced_element() const {
    for (const CoarseMaterialFit& fit : entries)
      if (fit.fitted) return fit.enhanced;
    return false;
  }
  bool compressed() const { return entries.size() < entry_of.size(); }
  // Digits per child: n, or n + 1 with void children.
  int digits() const { return num_materials() + (void_children ? 1 : 0); }
  // Base-digits() digits, child 0 least significant: the ids minus one, or
  // the ids themselves with void children; -1 if an id is out of range (a
  // void child in a database without void children).
  std::int64_t combination_code(const BlockMaterials& ids) const;
  BlockMaterials combination_ids(std::int64_t code) const;
  std::int64_t num_combinations() const;  // digits()^8
  // The fitted coarse material of a combination, or nullptr (a combination
  // the database does not hold, or one that could not be fitted).
  const CoarseMaterialFit* find(const BlockMaterials& ids) const;
  // Level 2: the fit for the level-1 entries of a cell's children.
  const CoarseMaterialFit& find_level2(const Arrangement& level1_entries) const;
  // Palette as materials: [0] = nullptr (void), [i] = NeoHookean(E_i, nu_i).
  std::vector<MaterialPtr> palette() const;
};

// Writes atomically (ArtifactWriter); `config_text` is the builder's
// resolved config, recorded as provenance.
void write_coarse_db(const std::string& path, const CoarseDatabase& db, const std::string& config_text,
                     const std::string& command_line, std::uint64_t seed, const std::string& executable);
// Reads and validates; InputError naming the file and field on any problem.
CoarseDatabase read_coarse_db(const std::string& path);

// The scene's palette must agree with the database's: each solid scene id i
// used by the grid must be Neo-Hookean with the database's E and nu for id i
// (relative tolerance 1e-9). InputError naming the id and the mismatch.
void check_scene_palette(const CoarseDatabase& db, const std::string& db_path,
                         const std::vector<MaterialPtr>& scene_palette, const std::vector<int>& used_ids);

// A level-1 database that may stand in for a level-2 database's compressed
// level-1 base (adaptive coarsening's level-1 cells): level 1, the same
// palette (E and nu per id), void children and coarse element as the base.
// InputError naming both files and the field that differs.
void check_level1_substitute(const CoarseDatabase& substitute, const std::string& substitute_path,
                             const CoarseDatabase& level2, const std::string& level2_path);
// Level-1 lookup for build_coarse_mesh: the database fit where it has one,
// `fallback` (naive coarsening) for the rest (blocks with a void child in a
// database without void children, and blocks that could not be fitted).
CoarseMaterialLookup database_coarsening(const CoarseDatabase& db, CoarseMaterialLookup fallback);

// Level-2 lookup for build_coarse_mesh on coarsen_grid(level1_grid): each
// child's level-1 combination to its level-1 entry, then the pairing
// stages. `fallback` (naive level-2 coarsening) where a child is all void
// or has no level-1 entry.
// The level-2 fit of a cell whose children are the level-1 combinations
// `ids` (index + 1 into level1_combinations, 0 = all void), or nullptr where
// database_coarsening_level2 falls back.
const CoarseMaterialFit* find_level2_fit(const CoarseDatabase& db, const std::vector<ChildIds>& level1_combinations,
                                         const ChildIds& ids);

CoarseMaterialLookup database_coarsening_level2(const CoarseDatabase& db, const CoarseGrid& level1_grid,
                                                CoarseMaterialLookup fallback);

}  // namespace msfab
