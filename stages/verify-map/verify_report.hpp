#pragma once
// The `msfab.verify_map` artifact (docs/artifacts.md, docs/verify_map.md):
// homogenized against full-resolution simulation of a mapped design, per
// load case of its scene.
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "verify/comparison.hpp"

namespace msfab {

inline constexpr const char* kVerifyMapSchema = "msfab.verify_map";
inline constexpr int kVerifyMapSchemaVersion = 1;

struct VerifyCase {
  std::string name;
  DisplacementComparison displacement;
  MatX homogenized;  // coarse nodes x 3
  double energy_homogenized = 0, energy_full = 0, relative_energy = 0;
  double solve_seconds_homogenized = 0, solve_seconds_full = 0;
  std::int64_t iterations_full = 0;  // CG iterations of the full solve (0 for a direct solver)
  std::int64_t point_loads = 0, load_fallbacks = 0, loaded_fine_nodes = 0;
};

struct VerifyReport {
  std::string fill;         // mapped | solid | tile
  int tile_structure = -1;  // fill tile: the structure every design cell holds
  int grid[3] = {0, 0, 0};
  double cell_size = 1;
  int resolution = 0;  // voxels per cell edge
  int tiling = 1;      // copies of its structure per cell edge (the mapping's)
  std::int64_t voxels = 0, material_voxels = 0;
  double void_ratio = 0;
  std::string void_model;  // remove | ersatz
  // void: remove: face-connected solid pieces of each model, those removed
  // because their supports leave a rigid motion free, and nodes fixed
  // because no solid voxel touches them (docs/verify_map.md).
  std::int64_t pieces_full = 0, removed_pieces_full = 0, removed_voxels_full = 0, inactive_nodes_full = 0;
  std::int64_t pieces_homogenized = 0, removed_pieces_homogenized = 0, removed_cells_homogenized = 0,
               inactive_nodes_homogenized = 0;
  int homogenized_elements = 1;  // hexahedra per cell edge in the homogenized model
  // Cells that meet only along an edge, both >= 10x stiffer than the cells
  // between them (topopt/edge_joints.hpp), in the homogenized model.
  std::int64_t edge_joints = 0;
  double edge_joint_largest_ratio = 0;
  std::string solver_homogenized, solver_full;  // as resolved by GridElasticity
  std::string coarse_space_full = "none";       // matrix-free: material | lattice
  std::int64_t unknowns_homogenized = 0, unknowns_full = 0;
  std::int64_t point_supports = 0, moved_point_supports = 0, lost_point_supports = 0;
  double seconds_model = 0;  // voxel model, stiffness and the transfer of supports
  double seconds_factorize_homogenized = 0,
         seconds_factorize_full = 0;  // assembly + factorization (matrix-free: setup)
  double seconds_total = 0;
  std::vector<VerifyCase> cases;
};

void write_verify_report(const std::string& path, const VerifyReport& report, const std::string& executable,
                         const std::string& config_text, const std::vector<std::string>& inputs, std::uint64_t seed);

}  // namespace msfab
