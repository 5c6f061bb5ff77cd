#pragma once
// Plots of a family discovery run (thesis Fig. 3-6, 3-7, 3-9): the Isomap
// embedding coloured by family, each family's coverage in the E–ν and ν–G'
// planes, and a picture per family of its representative and of the
// structure its template generates.
#include <string>

#include "families/families_artifact.hpp"
#include "gamut/microstructure_set.hpp"

namespace msfab {

// "run/x.families.h5" -> "run/x.plots"
std::string plot_folder_for(const std::string& out);

// Writes embedding.png, coverage_E_nu.png, coverage_nu_G.png and
// family<k>.png into `folder` (created if missing).
void write_family_plots(const std::string& folder, const FamiliesResult& result, const MicrostructureSet& set);

}  // namespace msfab
