#pragma once
// Geometric coarsening of dynamics-aware coarsening (thesis §4.3.1): refine
// a shape's hex discretization until its first modal frequencies converge,
// then pick the coarsest resolution whose first modes still match the
// convergent mesh's mode shapes to a relative Hausdorff tolerance. The
// frequencies of that coarse mesh are too high (numerical stiffening);
// dynamics/dac_calibration.hpp (Eq. 4.16-4.18) rescales its Young's modulus.
#include <array>
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
  double element_size = 0.0;    // sizes that decrease with the level allow the frequency extrapolation
};
using DacLevelBuilder = std::function<DacLevel(int level)>;

// Richardson extrapolation of one mode's frequency over three meshes,
// coarse to fine, element sizes h[0] > h[1] > h[2]: f(h) ~ f0 + c h^p with
// the order p observed from the three values (the fixed-point form for
// unequal refinement ratios of Celik et al., J. Fluids Eng. 130, 2008). It
// holds only where the sequence is in its asymptotic range, which shows as
// monotone convergence: both changes of one sign, the finer one smaller.
// Elsewhere (oscillating or growing changes) no limit can be claimed and
// the finest value is returned with `monotone` false. InputError unless
// the sizes decrease and every value is finite.
struct FrequencyLimit {
  double limit = 0.0;  // estimated converged frequency
  double order = 0.0;  // observed order p; 0 when not monotone
  bool monotone = false;
};
FrequencyLimit extrapolate_frequency(const std::array<double, 3>& f, const std::array<double, 3>& h);

struct DacOptions {
  int first_level = 0;
  int max_level = 6;
  int num_modes = 4;                    // modes whose shapes and frequencies must match
  double convergence_tolerance = 0.01;  // max relative frequency change between levels
  double shape_tolerance = 0.05;        // max relative Hausdorff distance per mode
  int match_window = 2;                 // see match_modes; extra modes are computed for it
  // The thesis's "accurate" mesh (§4.3.2, Fig. 4-11): frequencies of the
  // first num_modes modes within this fraction of their converged values.
  double accuracy_tolerance = 0.05;
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
  VecX frequencies;                // first num_modes + match_window, Hz
  double frequency_change = 0.0;   // max_i |f_i - f_i(previous)| / f_i over num_modes (0 at the first level)
  std::vector<ModeMatch> matches;  // mode i -> convergent mode and its relative Hausdorff distance
  double max_distance = 0.0;
  bool within_tolerance = false;  // every distance <= shape_tolerance
  // Relative distance of the first num_modes frequencies from their
  // estimated converged values (DacResult::limits): largest and mean.
  double limit_error = 0.0, mean_limit_error = 0.0;
  bool accurate = false;  // limit_error <= accuracy_tolerance
};

struct DacResult {
  std::vector<DacLevelReport> levels;  // first_level .. convergent level, in order
  bool converged = false;              // false: max_level reached first; the finest level is the reference
  int convergent_level = -1;
  int chosen_level = -1;    // coarsest level within the shape tolerance
  size_t chosen_index = 0;  // its position in `levels`
  // Converged frequency of each of the first num_modes modes (of the
  // reference level, tracked through coarser levels by shape): Richardson
  // extrapolation over the three finest levels where the mode converges
  // monotonically there, else the reference level's own frequency. A
  // convergent level still moves by up to convergence_tolerance, and one
  // stopped at max_level by more: the extrapolation says by how much.
  std::vector<FrequencyLimit> limits;
  // Coarsest level with `accurate`; -1 when none is (the reference level
  // itself may lie further than accuracy_tolerance from the limits).
  int accurate_level = -1;
  size_t accurate_index = 0;  // its position in `levels` (when accurate_level >= 0)
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
