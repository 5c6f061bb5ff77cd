#pragma once
// Online coarsening of a voxel design (thesis §2.4), shared by the static
// simulator and the dynamics simulator: the grid in 2^level blocks, each one
// coarse element whose quadrature-point materials come from a DDFEM
// database or from a baseline. What a stage then puts on the coarse mesh
// (static conditions, masses, clamps) is its own business.
#include <memory>
#include <string>
#include <vector>

#include "ddfem/coarse_db.hpp"
#include "ddfem/coarse_grid.hpp"

namespace msfab {

struct CoarseningRequest {
  int level = 0;                   // 0 = fine, 1, 2
  std::string material = "ddfem";  // ddfem | naive | averaged | homogenized | galerkin[-full] | matched
  std::string database;            // coarse_db path (ddfem)
  // ddfem: how blocks without a fit in the database are coarsened (naive |
  // galerkin[-full] | matched); blocks with void children are the usual ones.
  std::string fallback = "naive";
  // trilinear | enhanced (condensed bubble modes); empty: the database's
  // element for ddfem, trilinear otherwise.
  std::string element;
  // ddfem: > 0 checks every solid mixed block's fit against the block's own
  // homogenized stiffness and coarsens it by the matched model where their
  // stiffness_distance exceeds this (docs/ddfem.md, "Checked lookup"); 0: off.
  double check_tolerance = 0;
  // matched: > 0 carries each cell onto its stiffness among this many voxels
  // of its real neighbours (windowed_stiffness, one material set per cell)
  // instead of its periodic C^H; 0: off.
  int window = 0;
};

struct CoarsenedVoxels {
  CoarseGrid level1, grid;  // grid = the level requested
  VoxelMesh mesh;
  CoarseMeshStats stats;
  double seconds = 0;       // grid + lookups + mesh (the online coarsening time)
  int fallback_blocks = 0;  // ddfem: distinct combinations without a fit (coarsened by request.fallback)
  std::shared_ptr<CoarseDatabase> database;
  std::string element = "trilinear";  // the coarse element used (request resolved)
  std::string fallback = "naive";     // ddfem: how blocks without a fit were coarsened
  double check_tolerance = 0;         // ddfem: the checked lookup's tolerance (request resolved; 0: off)
  int checked_blocks = 0;             // ddfem with a check: distinct solid mixed blocks whose fit was checked
  int replaced_blocks = 0;            // ... and of those, coarsened by the matched model instead
  int unresolved_windows = 0;         // with a window: cells whose window gave no stiffness (own C^H used)
  int distinct_windows = 0;           // with a window: distinct windows among the solid cells (each computed once)
};

// A baseline by name (naive, averaged, galerkin, homogenized of
// ddfem/baseline_coarsening.hpp, matched of ddfem/matched_coarsening.hpp):
// of level-1 blocks when level1 is null, of level-2 cells of that level-1
// grid otherwise; `enhanced`: the coarse element has bubble modes.
CoarseMaterialLookup baseline_coarsening(const std::string& name, const std::vector<MaterialPtr>& palette,
                                         const CoarseGrid* level1, bool enhanced = false);

// The ddfem lookup of coarsen_voxels for `db` (a level-1 database, or a
// level-2 one over `level1`), with the element, fallback and check of
// `settings`; counts the fallback, checked and replaced blocks into `counts`
// (may be null). Adaptive coarsening builds its levels' lookups with it.
CoarseMaterialLookup ddfem_lookup(const CoarseDatabase& db, const std::vector<MaterialPtr>& palette,
                                  const CoarseGrid& level1, int level, const CoarsenedVoxels& settings,
                                  CoarsenedVoxels* counts);

// `palette` is indexed by voxel id ([0] = void). InputError for a bad
// request: unknown material or fallback, a level other than 1 or 2, ddfem
// without a database or with a database of another level, a database whose
// palette disagrees with the grid's materials, an element other than the one
// the database was fitted for. Option names in the messages are the
// command-line ones (--coarsen, --coarse-material, ...).
CoarsenedVoxels coarsen_voxels(const VoxelGrid& grid, const std::vector<MaterialPtr>& palette,
                               const CoarseningRequest& request);

}  // namespace msfab
