#pragma once
// The `msfab.design` artifact (docs/artifacts.md): the topology optimizer's
// result on a regular grid of cells, read by the microstructure mapper.
//
// Cells are numbered i + nx (j + ny k) (nz = 1 for a 2D design). Each cell
// holds its material parameters both raw and normalized to the unit cube of
// the design's material space. For a gamut space (cubic3d, cubic2d,
// orthotropic2d) the normalization is the gamut's (MaterialSpace), so the
// mapper compares a cell's `unit` row with a microstructure's `unit` row
// directly.
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "gamut/space_label.hpp"

namespace msfab {

inline constexpr const char* kDesignSchema = "msfab.design";
inline constexpr int kDesignSchemaVersion = 1;

// What a cell of the design domain is allowed to be.
enum class CellRole : std::uint8_t { design = 0, empty = 1, solid = 2 };

struct DesignHistoryEntry {
  int iteration = 0;
  double objective = 0;      // the full objective S (elasticity terms + mass terms)
  double elastic = 0;        // the weighted elasticity terms alone (compliance / target error)
  double max_violation = 0;  // max over cells of the gamut constraint Phi (or volume excess)
  double seconds = 0;        // wall time since the start
};

// The space (SpaceLabel::space) is one of cubic3d | cubic2d | orthotropic2d |
// isotropic2d | isotropic3d | analytic2d | analytic3d | simp2d | simp3d.
struct Design : SpaceLabel {
  int dimension = 2;  // 2 or 3
  int nx = 0, ny = 0, nz = 1;
  double cell_size = 1.0;       // cell edge length (m)
  MatX unit;                    // cells x properties, normalized parameters
  MatX raw;                     // cells x properties, raw parameters (moduli in Pa)
  std::vector<CellRole> roles;  // per cell
  VecX phi;                     // per cell, the gamut constraint value at the end (<= 0 inside)
  MatX displacement;            // nodes x dimension, the first load case's solution
  std::vector<DesignHistoryEntry> history;
  // A design in a family's own parameters (topopt space family3d; the cells
  // above then hold the cubic3d material they interpolate): the parameter
  // names, their values normalized to [0, 1] along the family's grid, and
  // raw (beam half-sizes). Empty otherwise.
  std::vector<std::string> family_names;
  MatX family_unit, family_raw;  // cells x family parameters

  std::int64_t cells() const { return std::int64_t(nx) * ny * nz; }
  std::int64_t nodes() const { return std::int64_t(nx + 1) * (ny + 1) * (dimension == 3 ? nz + 1 : 1); }
};

// Throws InputError naming the field for inconsistent sizes.
void write_design_artifact(const std::string& path, const Design& design, const std::string& executable,
                           const std::string& config_text, const std::vector<std::string>& inputs, std::uint64_t seed);
// InputError naming the file and field on anything missing or inconsistent.
Design read_design_artifact(const std::string& path);

// True for the spaces a gamut (and a microstructure set) can live in.
bool is_gamut_space(const std::string& space);

}  // namespace msfab
