#pragma once
// The continuous step of the gamut sampler (thesis §3.2.2, Eq. 3.4): a
// structure near the gamut boundary is relaxed to densities 0.5 +- 0.3 and
// pushed towards a target tensor just outside the gamut by topology
// optimization, then thresholded back to voxels.
//
//   x        one density in [0, 1] per orbit of the cell symmetry (the
//            fundamental domain), so every iterate keeps the symmetry
//   x~       the densities filtered with a periodic cone of radius R voxels
//            (x~ = H x / sum H), the filter against thin features
//   K_v      K_soft + x~_v^p (K_stiff - K_soft), SIMP with p = 3; a void
//            soft phase is the stiff one scaled by void_stiffness
//   f(x)     |W (G(x) - G0) W|_F^2 + w_rho (rho(x) - rho0)^2, W = G0^(-1/2),
//            G = (C^H)^-1 (the in-plane 3 x 3 block for a 2D cell); the
//            thesis writes (G - G0)^2; weighting by the target makes
//            every eigenmode count relative to its own size (the shear
//            compliance of a soft cell would otherwise decide alone)
//            rho = mean of x~ (the stiff fraction)
//   min f    NLopt MMA, at most max_iterations evaluations, bounds [0, 1];
//            the best iterate is kept (MMA's objective oscillates)
//
// The gradient is exact: dC^H/dx~_v = p x~_v^(p-1) U_v^T (K_stiff - K_soft)
// U_v / |Y| with U_v the total corner displacements (the fluctuations are
// stationary), dG = -G dC G, then the filter and the orbit sums by the
// chain rule. We filter densities rather than sensitivities: MMA's
// conservative inner iterations compare objective values, and a filtered
// sensitivity is not the gradient of any objective (docs/gamut.md).
#include <Eigen/Eigenvalues>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "core/types.hpp"
#include "fem/voxel_grid.hpp"
#include "gamut/material_space.hpp"
#include "gamut/structure_ops.hpp"
#include "material/material.hpp"

namespace msfab {

struct ContinuousOptions {
  int max_iterations = 50;       // objective evaluations
  double penalty = 3.0;          // SIMP exponent p
  double filter_radius = 1.5;    // voxels; <= 1: no filtering
  double density_weight = 1.0;   // w_rho
  double start_offset = 0.3;     // stiff voxels start at 0.5 + offset, others at 0.5 - offset
  double void_stiffness = 1e-6;  // when the soft phase is void
  // Heaviside projection with continuation: beta = 1, 2, 4, ... up to
  // projection_beta, the evaluations split evenly over the stages, so the
  // last stage optimizes a nearly black-and-white design and the
  // thresholded structure keeps the properties MMA found. 0: none.
  double projection_beta = 0;
  // The printer's minimum feature size in voxels (thin_feature_voxels):
  // a directed push keeps only thresholds whose structure has none.
  int min_feature = 1;
  // Target objective: the levels x~ is thresholded at; the printable
  // structure (mirrored, cleaned, no feature below min_feature) whose own
  // objective is lowest is kept. The gamut's continuous step uses 0.5
  // alone; a structure generated at a design's target tries several,
  // since the grey optimum and its thresholded structure differ.
  std::vector<double> threshold_levels = {0.5};
  // Per voxel (empty: none), 1 for voxels held stiff throughout: a face
  // connector shared by neighbouring cells (face_connector). Must be
  // invariant under the cell symmetry.
  std::vector<std::uint8_t> frozen_stiff;
  CellSymmetry symmetry = CellSymmetry::cubic;
  // Cell problems on the symmetric part (one octant, two cases if cubic;
  // exact); false: six cases on the whole cell, for comparison.
  bool use_symmetry = true;
};

struct RefinementTarget {
  MatX G;            // 6 x 6 (3D) or the 3 x 3 plane block (2D cell), Voigt, engineering shear
  double rho = 0.5;  // stiff volume fraction
};

// A directed objective (the outward push of §3.2.2 with a chosen
// direction instead of the level set's normal): maximize d . u(C^H, rho),
// u the cell's properties in the unit cube of a material space, subject to
// floors u_i >= floor_i (MMA inequality constraints). "Minimize nu at
// fixed E" is d = -e_nu with a floor on E; the floors keep the push from
// buying its direction with a collapse of the stiffness.
struct DirectedTarget {
  VecX direction;  // in the space's unit cube, one entry per property
  VecX floor;      // unit-cube lower bounds; -inf (or below 0) for none
};

// The objective of one cell, for a two-phase structure of `stiff` and
// `soft` (soft == nullptr: void). Cells are cubic/square (cubic
// symmetry) or any box (orthotropic). InputError on bad options or a
// target of the wrong size.
class ContinuousCellProblem {
 public:
  // The target objective, Eq. 3.4.
  ContinuousCellProblem(int nx, int ny, int nz, double h, MaterialPtr stiff, MaterialPtr soft,
                        const RefinementTarget& target, const ContinuousOptions& options);
  // The directed objective f = -d . u with the floors as constraints. The
  // space's kind must match the cell (2D space: nz = 1).
  ContinuousCellProblem(int nx, int ny, int nz, double h, MaterialPtr stiff, MaterialPtr soft,
                        const MaterialSpace& space, const DirectedTarget& target, const ContinuousOptions& options);

  int variables() const { return static_cast<int>(orbit_voxels_.size()); }
  // Whether design variable `orbit` is held at 1 (options.frozen_stiff).
  bool frozen(int orbit) const { return !frozen_orbit_.empty() && frozen_orbit_[std::size_t(orbit)]; }
  // Densities of the voxels of a structure (stiff id -> 0.5 + offset, others 0.5 - offset), one per orbit.
  std::vector<double> start(const VoxelGrid& structure, int stiff_id) const;
  // Filtered per-voxel densities x~.
  std::vector<double> filtered(const std::vector<double>& x) const;
  // The projection's sharpness beta (0: none); the stiffness weights and
  // rho then use the projected densities H_beta(x~).
  void set_projection(double beta);
  // f(x); fills `gradient` (size variables()) when non-null.
  double objective(const std::vector<double>& x, std::vector<double>* gradient) const;
  // The directed objective's floors as constraints c(x) = floor - u <= 0.
  int constraints() const { return static_cast<int>(floors_.size()); }
  double constraint(int c, const std::vector<double>& x, std::vector<double>* gradient) const;
  // The unit-cube properties u of the (grey) design; directed problems only.
  VecX unit_properties(const std::vector<double>& x) const;
  // Directed problems: the unit-cube properties of a black-and-white
  // structure (stiff_id stiff, all else soft), and how far u falls below
  // the floors (0: none).
  VecX structure_unit_properties(const VoxelGrid& structure, int stiff_id) const;
  double floor_violation(const VecX& u) const;
  // Target problems: the objective f of a black-and-white structure
  // (stiff_id stiff, all else soft).
  double structure_objective(const VoxelGrid& structure, int stiff_id) const;
  double directed_objective(const VecX& u) const { return -direction_.dot(u); }
  bool directed() const { return space_.has_value(); }
  // Voxel ids of the thresholded design: x~ >= level -> stiff_id, else soft_id.
  VoxelGrid threshold(const std::vector<double>& x, int stiff_id, int soft_id, double level = 0.5) const;

 private:
  struct Evaluation;
  int nx_, ny_, nz_;
  double h_;
  Mat24 K_stiff_, K_soft_;
  RefinementTarget target_;
  MatX W_;
  std::optional<MaterialSpace> space_;  // set for a directed objective
  VecX direction_;
  std::vector<std::pair<int, double>> floors_;  // (property, unit floor)
  ContinuousOptions options_;
  std::vector<int> orbit_of_voxel_;
  std::vector<std::vector<int>> orbit_voxels_;
  std::vector<std::uint8_t> frozen_orbit_;  // per orbit, options.frozen_stiff
  // The filter on the periodic cell is one stencil: (neighbour offset, each
  // in [0, n) along its axis, weight / sum) the same for every voxel, in
  // the order of first occurrence. Rows stored per voxel took
  // O(taps^2) to build and 16 bytes per tap and voxel: minutes and ~9 GB
  // at 64^3 with a radius of 8 voxels.
  struct FilterTap {
    int dx, dy, dz;
    double weight;
  };
  std::vector<FilterTap> filter_;
  // Calls f(v, w, weight) for every voxel v and filter tap (neighbour w), in
  // the order of v, then the taps.
  template <typename F>
  void for_each_filter_tap(F&& f) const;
  // The last design evaluated: NLopt asks for the objective and each
  // constraint at the same x, and each needs the same homogenization.
  mutable std::shared_ptr<Evaluation> last_;
  double beta_ = 0;

  double project(double xt, double* derivative) const;
  void setup_cell(MaterialPtr stiff, MaterialPtr soft);
  void homogenize_densities(Evaluation& e) const;                                   // e.xp -> e.r, e.C, e.rho
  double target_objective(const Evaluation& e) const;                               // f of a target problem
  Evaluation homogenize_structure(const VoxelGrid& structure, int stiff_id) const;  // black and white
  const Evaluation& evaluate(const std::vector<double>& x, bool with_sensitivities) const;
  // d(property)/dC of the plane block or the 6 x 6 tensor, and the unit-cube properties.
  VecX properties_and_gradients(const Evaluation& e, std::vector<MatX>* dudC) const;
  // The gradient over the design variables of a function with df/dC (m x m) and df/drho.
  void chain(const Evaluation& e, const MatX& dfdC, double dfdrho, std::vector<double>* gradient) const;
};

struct ContinuousResult {
  VoxelGrid structure;  // thresholded, mirrored and cleaned
  double start_objective = 0, best_objective = 0;
  int evaluations = 0;
  double threshold = 0.5;       // the level x~ was thresholded at
  bool found = true;            // false when no level gave a printable structure (directed, or several target levels)
  std::vector<double> history;  // f per evaluation
};

// Runs MMA from `structure` towards `target`. Deterministic.
ContinuousResult refine_structure(const VoxelGrid& structure, int stiff_id, int soft_id, MaterialPtr stiff,
                                  MaterialPtr soft, const RefinementTarget& target,
                                  const ContinuousOptions& options = {});
// Runs MMA from `structure` along a directed objective; the best feasible
// iterate (floors met to 1e-3) is thresholded at the level whose printable
// structure (mirrored, cleaned, no feature below min_feature) is best with
// the floors met, or, if no level meets them, comes closest; found = false
// and an all-soft cell when no level gives a printable structure.
// Deterministic.
ContinuousResult refine_structure_directed(const VoxelGrid& structure, int stiff_id, int soft_id, MaterialPtr stiff,
                                           MaterialPtr soft, const MaterialSpace& space, const DirectedTarget& target,
                                           const ContinuousOptions& options = {});

}  // namespace msfab
