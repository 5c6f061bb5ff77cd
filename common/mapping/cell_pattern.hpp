#pragma once
// Designs written by hand (thesis Table 3.1, Figs 3-22 and 3-23): every
// design cell of a scene is given a structure of a microstructure set by a
// pattern instead of by optimization: one structure everywhere (a periodic
// tiling), layers of structures, or structures drawn at random. The
// result is an ordinary `msfab.design` whose targets are the structures'
// own properties, so msfab-map (with one candidate) and msfab-verify-map
// treat it like an optimized design. This separates the homogenization's
// own error (scale separation, boundary layers, mismatched neighbours)
// from the optimizer's choices.
#include <cstdint>
#include <string>
#include <vector>

#include "gamut/microstructure_set.hpp"
#include "topopt/cell_grid.hpp"
#include "topopt/design_artifact.hpp"

namespace msfab {

enum class PatternKind { uniform, layers, random };

struct CellPattern {
  PatternKind kind = PatternKind::uniform;
  std::vector<std::int32_t> structures;  // indices into the set (uniform: exactly one)
  int axis = 2;                          // layers: normal axis, 0 x, 1 y, 2 z
  int thickness = 1;                     // layers: cells per layer
  std::uint64_t seed = 0;                // random: cell c takes structures[hash(seed, c) % size]
};

// Per cell the structure index of the pattern; -1 for cells whose role is
// not `design`. Layer l (cell coordinate along `axis` divided by
// `thickness`) takes structures[l % size]. std::invalid_argument for an
// empty list, a uniform pattern with more than one structure, a bad axis
// or thickness, or a role list of the wrong size.
std::vector<std::int32_t> pattern_structures(const CellGrid& grid, const std::vector<CellRole>& roles,
                                             const CellPattern& pattern);

// The design whose cells' targets are their structures' properties (raw
// and unit rows of the set). Forced solid cells get density 1 and all
// else 0 (as msfab-topopt writes them), phi is 0 (no gamut constraint was
// evaluated) and there is no history or displacement. InputError naming
// `set_path` if an index is outside the set, or the set's dimension does
// not match the grid's.
Design assigned_design(const CellGrid& grid, const std::vector<CellRole>& roles,
                       const std::vector<std::int32_t>& structure, const MicrostructureSet& set,
                       const std::string& set_path);

}  // namespace msfab
