#pragma once
// The `msfab.mapped` artifact (docs/artifacts.md, docs/mapping.md): which
// microstructure, and which of its two exemplars, fills every cell of a
// design, with the boundary mismatch the choice leaves.
//
// Cells are numbered i + nx (j + ny k), as in `msfab.design`. The structure
// indices refer to the `msfab.microstructures` artifact recorded among the
// inputs (its path and SHA-256 are in the root attribute `inputs`).
#include <cstdint>
#include <string>
#include <vector>

#include "topopt/design_artifact.hpp"

namespace msfab {

inline constexpr const char* kMappedSchema = "msfab.mapped";
inline constexpr int kMappedSchemaVersion = 1;
inline constexpr int kMaxTiling = 16;  // copies of a structure per cell edge

struct MappedDesign {
  std::string space;  // the design's (and the set's) material space
  std::vector<std::string> property_names;
  int dimension = 2;
  int nx = 0, ny = 0, nz = 1;  // cells
  double cell_size = 1.0;      // cell edge (m)
  int vx = 0, vy = 0, vz = 1;  // voxels per structure (the structures' size)
  // Copies of its structure per cell edge (thesis §3.6: a cell replaced by
  // a tiling of its microstructure, which shrinks the boundary layers the
  // periodic homogenization leaves out): a cell is tiling x vx voxels wide
  // (and tiling x vz high in 3D; a 2D model stays one voxel thick).
  int tiling = 1;
  std::vector<CellRole> roles;          // per cell, from the design
  std::vector<std::int32_t> structure;  // per cell, index into the set; -1 for forced empty / solid cells
  std::vector<std::uint8_t> shift;      // per cell, 1: the half-shifted exemplar
  std::vector<double> distance;         // per cell, |unit(structure) - unit(target)|; 0 for fixed cells
  // Per cell, |C(structure) - C(target)|_F / |C(target)|_F with C the
  // space's stiffness tensor of the raw properties: the property gap the
  // printed cell has against what the optimizer used; 0 for fixed cells.
  // Empty when read from an artifact written before it existed (or for a
  // set whose properties are not the space's).
  std::vector<double> property_gap;
  std::vector<std::int32_t> candidates;    // per cell, candidate structures considered (0 for fixed cells)
  std::vector<std::int64_t> mismatch;      // per cell, the final I_i (with a void-pair cost: its energy)
  std::vector<std::int64_t> history;       // total I after each accepted move; [0] the initial one
  std::vector<std::int64_t> history_cell;  // the cell each move changed; [0] = -1

  // The settings the mapping ran with, and what it cost.
  int k = 16;
  double radius = 0;  // 0: none
  bool half_shift = true;
  double max_distance = 0.1;
  double void_pair_cost = 0;  // MismatchProblem; 0 in artifacts written before it existed
  // Voxel pairs across the faces between cells, each once: differing, void
  // on both sides, the same material on both sides (-1: not recorded).
  std::int64_t mismatch_pairs = -1, void_pairs = -1, contact_pairs = -1;
  std::int64_t evaluations = 0;
  double seconds = 0;

  std::int64_t cells() const { return std::int64_t(nx) * ny * nz; }
};

// Throws std::invalid_argument for inconsistent sizes (a bug of the caller).
void write_mapped_artifact(const std::string& path, const MappedDesign& mapped, const std::string& executable,
                           const std::string& config_text, const std::vector<std::string>& inputs, std::uint64_t seed);
// InputError naming the file and field on anything missing or inconsistent.
MappedDesign read_mapped_artifact(const std::string& path);

}  // namespace msfab
