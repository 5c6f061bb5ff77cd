#pragma once
// The `msfab.result` artifact of msfab-simulate (docs/artifacts.md).
#include <array>
#include <string>
#include <vector>

#include "fem/voxel_grid.hpp"
#include "scene/scene.hpp"
#include "solve/newton.hpp"

namespace msfab {

constexpr const char* kResultSchema = "msfab.result";
constexpr int kResultSchemaVersion = 1;

struct SimulationRecord {
  const Scene* scene = nullptr;
  const VoxelMesh* mesh = nullptr;
  const StaticConditions* conditions = nullptr;
  const NewtonResult* newton = nullptr;
  double setup_seconds = 0;
  std::string config_text;
  // Artifacts the run read (database, fine reference): recorded with their hashes.
  std::vector<std::string> inputs;
  std::string command_line;
  std::uint64_t seed = 0;
  // Coarsened runs (level > 0): the mesh is the coarse one.
  int coarsen_level = 0;
  std::string coarse_material;                  // ddfem | naive | averaged | homogenized | galerkin[-full] | matched
  std::string coarse_fallback;                  // ddfem: naive | galerkin[-full] | matched, for blocks without a fit
  int fallback_blocks = 0;                      // ddfem: distinct blocks coarsened by the fallback
  double check_tolerance = 0;                   // ddfem: --coarse-check (0: no check)
  int checked_blocks = 0, replaced_blocks = 0;  // ddfem with a check: solid mixed blocks checked, replaced
  int window = 0, unresolved_windows = 0;       // --coarse-window, cells left on their own C^H
  int distinct_windows = 0;                     // --coarse-window: distinct windows, each computed once
  std::string coarse_element = "trilinear";     // trilinear | enhanced
  std::string database;                         // ddfem: the coarse_db path
  double coarsening_seconds = 0;
  int fine_elements = 0;
  // Adaptive runs (--target-error; coarsen_level is 2, the coarsest level used).
  bool adaptive = false;
  double target_error = 0, predicted_error = 0;
  double a_posteriori_error = 0;      // the kept mixed solve's a-posteriori estimate
  std::string a_posteriori_source;    // what that estimate is (the extrapolation, a bound, a fine Newton step)
  int adaptive_solves = 0;            // mixed solves (more than one where the a-posteriori check missed)
  double rejected_solve_seconds = 0;  // Newton time of the mixed solves that were not kept
  double uniform_solve_seconds = 0;   // the level-2 and level-1 solves the levels are chosen from
  double level_difference = 0;        // mean-vertex distance between those two solutions
  std::string level1_database;        // --level1-database (empty: the level-2 database's base)
  std::array<int, 3> elements_per_level{};
  // With --compare-fine: the fine reference run and the §2.5.2 error.
  bool compared = false;
  double fine_seconds = 0, error_vs_fine = 0;
  // Uniform coarsening only: the smallest error any model on this coarse
  // mesh can have (ddfem/coarsening_error.hpp), and its certified lower bound.
  bool has_error_floor = false;
  double error_floor = 0, error_floor_lower_bound = 0;
};

// A fine run read back for comparison: displacements (3 per node of `fine`)
// and its Newton time. InputError if the file is not a fine result of a mesh
// with the same nodes.
struct FineReference {
  VecX displacement;
  double newton_seconds = 0;
};
FineReference read_fine_reference(const std::string& path, const VoxelMesh& fine);

// Writes the artifact atomically to `path` and its XDMF sidecar next to it;
// returns the sidecar's path.
std::string write_result_artifact(const std::string& path, const SimulationRecord& record);

}  // namespace msfab
