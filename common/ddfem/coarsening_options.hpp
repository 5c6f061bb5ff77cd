#pragma once
// The command-line options of online coarsening, shared by the stages that
// coarsen a voxel design (msfab-simulate, msfab-dynamics), so both spell
// and check them alike.
#include "cli/stage_app.hpp"
#include "ddfem/voxel_coarsening.hpp"

namespace msfab {

// --coarsen, --coarse-material, --database, --coarse-fallback, and with
// `element_option` --coarse-element, all writing into `request`.
void add_coarsening_options(StageApp& app, CoarseningRequest& request, bool element_option);

}  // namespace msfab
