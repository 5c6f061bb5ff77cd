#pragma once
// Geometric coarsening of dynamics-aware coarsening (thesis §4.3.1): refine
// a shape's hex discretization until its first modal frequencies converge,
// then pick the coarsest resolution whose first modes still match the
// convergent mesh's mode shapes to a relative Hausdorff tolerance. The
// frequencies of that coarse mesh are too high (numerical stiffening);
// dynamics/dac_calibration.hpp (Eq. 4.16-4.18) rescales its Young's modulus.
#include <functional>
#include <string>
#include <vector>

#include "dynamics/modal_analysis.hpp"
#include "dynamics/mode_shape_distance.hpp"
#include "fem/hex_mesh.hpp"

namespace msfab {

// One discretization of the shape, as built by the caller for a level
// (larger level = finer mesh, e.g. 2^level voxels per unit length).
struct DacLevel {
  HexMesh mesh;
  std::vector<double> density;  // per element, kg/m^3
  std::vector<char> fixed;      // per DOF (1 = clamped), or empty for a free body
  double element_size = 0.0;    // reported only
};
using DacLevelBuilder = std::function<DacLevel(int level)>;

struct DacOptions {
  int first_level = 0;
  int max_level = 6;
  int num_modes = 4;                   // modes whose shapes and frequencies must match
  double convergence_tolerance = 0.01;  // max relative frequency change between levels
  double shape_tolerance = 0.05;        // max relative Hausdorff distance per mode
  int match_window = 2;                 // see match_modes; extra modes are computed for it
  // Modal solver settings; num_modes is overridden, and rigid modes are
  // always skipped (a mesh without enough clamped DOFs has them).
  ModalOptions modal;
  ModeDistanceOptions distance;
};

struct DacLevelReport {
  int level = 0;
  int elements = 0;
  int dofs = 0;
  double element_size = 0.0;
  VecX frequencies;              // first num_modes + match_window, Hz
  double frequency_change = 0.0;  // max_i |f_i - f_i(previous)| / f_i over num_modes (0 at the first level)
  std::vector<ModeMatch> matches; // mode i -> convergent mode and its relative Hausdorff distance
  double max_distance = 0.0;
  bool within_tolerance = false;  // every distance <= shape_tolerance
};

struct DacResult {
  std::vector<DacLevelReport> levels;  // first_level .. convergent level, in order
  bool converged = false;  // false: max_level reached first; the finest level is the reference
  int convergent_level = -1;
  int chosen_level = -1;   // coarsest level within the shape tolerance
  size_t chosen_index = 0; // its position in `levels`
  ModalResult chosen_modes, convergent_modes;
};

// Builds levels first_level, first_level + 1, ... and computes their modes
// until the frequency change drops below convergence_tolerance (or
// max_level), then compares every level's first num_modes shapes with the
// convergent mesh's. Every level's modes are already known from the
// refinement sweep, so the coarsest acceptable one is found by scanning up
// from the coarsest instead of bisecting. InputError for invalid options;
// errors of the builder and the modal solver propagate.
DacResult dac_geometric_coarsening(const DacLevelBuilder& build, const DacOptions& options = {});

}  // namespace msfab
