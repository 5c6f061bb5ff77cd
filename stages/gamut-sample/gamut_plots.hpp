#pragma once
// PNG plots of a sampling run (like thesis Fig. 3-14): the structures'
// Young's modulus (log, relative to the stiff material) against Poisson's
// ratio with the projected gamut boundary, the relative shear modulus
// against both, and coverage per cycle.
#include <string>
#include <vector>

#include "gamut/gamut_artifact.hpp"
#include "gamut/material_space.hpp"
#include "gamut/microstructure_set.hpp"

namespace msfab {

// The boundary drawn is the zero contour of min Phi over the other
// properties (the projection of the gamut onto the E-nu plane).
void plot_gamut_projection(const std::string& path, const MicrostructureSet& set, const GamutLevelSet& gamut,
                           const MaterialSpace& space, const std::string& title);
// The other two views of a cubic gamut (thesis §3.3): log E against the
// relative shear modulus G' = 2 (1 + nu) G / E (1 for an isotropic
// material), and nu against G'. Structures only: G' is not a coordinate of
// the level set. Written as <stem>_E_G.png and <stem>_nu_G.png; nothing for
// an orthotropic space.
void plot_shear_projections(const std::string& stem, const MicrostructureSet& set, const MaterialSpace& space);
void plot_coverage(const std::string& path, const std::vector<GamutCycle>& history);

}  // namespace msfab
