#pragma once
// The starting design of msfab-topopt: uniform (`initial.rho`, moved inside
// the space's constraint) or a coarser design of the same space resampled
// onto this grid (`initial.design`, the coarse-to-fine continuation of
// thesis §3.6.3: each cell takes the parameters of the coarse cell its
// centre falls in).
#include <cstdint>
#include <string>
#include <vector>

#include "io/config.hpp"
#include "topopt/cell_grid.hpp"
#include "topopt/cell_material.hpp"
#include "topopt/design_artifact.hpp"

namespace msfab {

struct DesignStart {
  std::string path;  // the coarse design read, if any
  MatX per_cell;     // grid cells x parameters, unit coordinates
  MatX rows(const std::vector<std::int64_t>& design_cells) const;
};

DesignStart read_design_start(const Config& config, const CellMaterialModel& model, const CellGrid& grid);

}  // namespace msfab
