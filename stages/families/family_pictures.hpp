#pragma once
// Pictures of a family discovery run (thesis Fig. 3-6, 3-7): per family, its
// representative next to the structure its template generates. The
// embedding and the coverage in the E–ν and ν–G' planes are drawn by
// `python3 -m msfab report` from the artifact (docs/python.md).
#include <string>

#include "families/families_artifact.hpp"
#include "gamut/microstructure_set.hpp"

namespace msfab {

// "run/x.families.h5" -> "run/x.plots"
std::string picture_folder_for(const std::string& out);

// Writes family<k>.png into `folder` (created if missing).
void write_family_pictures(const std::string& folder, const FamiliesResult& result, const MicrostructureSet& set);

}  // namespace msfab
