#pragma once
// Fitting the coarse material of one block (thesis Eq. 2.7-2.9).
//
// Coarse model: at each of the 8 Gauss points k of the coarse element a
// Neo-Hookean density with (mu_k, lambda_k) plus the spring of Eq. 2.7 with
// direction v_k (from anisotropy.hpp) and stiffness C_k. Here C_k is stored
// as an energy DENSITY, weighted by w_k det J_k like the Neo-Hookean term;
// Eq. 2.7's unweighted constant is w_k det J_k C_k. This keeps C_k in the
// units of mu_k, independent of the element size, and makes
// hex_energy(QuadratureMaterials) reproduce the fitted energy exactly.
//
// The energy is linear in p = (mu_k, lambda_k, C_k)_k:
//   V^1(u) = sum_k w_k det J_k [mu_k ((I1 - 3)/2 - log J) + lambda_k (log J)^2 / 2
//                               + C_k (||F_k v_k|| - 1)^2],
// so Eq. 2.9 is a regularized linear least-squares problem with p >= 0,
// solved by NNLS in scaled variables (see docs/ddfem.md, "Fitting").
//
// Optionally (CoarseFitOptions::centre_point) a Neo-Hookean term at the
// element centre,
//   + V_e [mu_c ((I1_c - 3)/2 - log J_c) + lambda_c (log J_c)^2 / 2],
// F_c the deformation gradient at chi = 0: the one-point element of reduced
// integration, with the 8 Gauss-point terms as its fitted hourglass control.
// A bent trilinear element shears parasitically and changes volume at its
// Gauss points but not at its centre, so the fit can move stiffness there
// instead of softening every point to offset locking (docs/ddfem.md,
// "Centre point").
//
// Optionally (CoarseFitOptions::enhanced_element) the fit is for the coarse
// element with three condensed bubble modes (hex8::enhanced_element_geometry),
// whose energy min_A V^1(u, A) is no longer linear in p. The fit then
// alternates: bubble amplitudes A_s of every sample for the current
// parameters, then the linear fit of p with the A_s held fixed, starting from
// the fine materials at their points (docs/ddfem.md, "Fit on the enhanced
// element"). The online coarse mesh must use the same element.
#include <array>
#include <cstdint>
#include <string>

#include "ddfem/anisotropy.hpp"
#include "ddfem/force_samples.hpp"
#include "fem/hex_element.hpp"

namespace msfab {

struct CoarseFitOptions {
  ForceSamplingOptions sampling;
  AnisotropyOptions anisotropy;
  bool anisotropic = true;        // fit C_k (else C_k = 0 and no direction solves)
  bool centre_point = false;      // fit mu_c, lambda_c (else both 0)
  bool enhanced_element = false;  // fit the element with condensed bubble modes
  int bubble_rounds = 8;          // enhanced: most alternations of bubbles and parameters
  double regularization = 0.02;   // lambda of Eq. 2.9, on the scaled problem, per 8 points
  double heldout_fraction = 0.2;  // samples kept out of the fit for validation
  // Weight of each force kind in the fit, indexed by ForceKind (stretch,
  // shear, bend, twist, pinch), whatever its sample count. Pinching, a point
  // load at two corners that a coarse element inside a body rarely sees,
  // weighs a tenth (see docs/ddfem.md, "Fitting"). Zero drops a kind.
  std::array<double, 5> kind_weight{1.0, 1.0, 1.0, 1.0, 0.1};
  // Fit blocks whose children are not all one material on the stretch and
  // shear samples only. A periodic sample of a non-uniform deformation
  // (bend, twist, pinch) gives every copy of the block the same
  // fluctuation; that is exact for a block of one material (no fluctuation)
  // but over-constrains a mixed block, whose neighbours in a bent body
  // deform differently, and the fit stiffens it (docs/ddfem.md, "Affine
  // samples on the enhanced element"). Level 1; meant for periodic sampling.
  bool mixed_blocks_affine_only = false;
  // How a sample's energy error enters the data term. relative: against the
  // sample's own fine energy, (V1 - V0) / V0, so small and large loads count
  // alike. absolute: Eq. 2.8 as written, (V1 - V0) / V_ref with one V_ref for
  // the block (the weighted RMS fine energy of its training samples, which
  // keeps the regularizer's scale), so the largest loads dominate.
  enum class Residual { relative, absolute };
  Residual residual = Residual::relative;
  // Share each kind's weight among its samples, so that a kind counts the
  // same whatever its sample count. false: every sample weighs its kind's
  // weight, as in Eq. 2.8's plain sum (with unit weights, kinds with more
  // patterns count more).
  bool balance_kinds = true;
  std::uint64_t split_seed = 11;
};

// "relative", "absolute"; parse_fit_residual throws InputError on anything else.
std::string fit_residual_name(CoarseFitOptions::Residual residual);
CoarseFitOptions::Residual parse_fit_residual(const std::string& name);

struct CoarseMaterialFit {
  bool fitted = false;
  std::string not_fitted_reason;  // why, when !fitted (e.g. a void child)
  BlockMaterials material_ids{};
  // Per coarse quadrature point: 8 at level 1 (2 x 2 x 2 Gauss points),
  // 64 for a 4-point rule.
  std::vector<double> mu, lambda, C;
  std::vector<Vec3> v;                      // spring directions (unit)
  double mu_centre = 0, lambda_centre = 0;  // mu_c, lambda_c (energy densities), 0 without the centre point
  bool enhanced = false;                    // fitted for (and used on) the element with bubble modes
  int bubble_rounds = 0;                    // enhanced: alternations run
  std::vector<double> mu0, lambda0;         // fine parameters at each point (Eq. 2.9's p^0)
  // Relative energy errors (V1 - V0) / V0, RMS with the fit's kind weights.
  double residual = 0;              // over the training samples
  double objective = 0;             // Eq. 2.9 as minimized: weighted data term + regularizer (scaled units)
  double heldout_error = 0;         // over the held-out samples
  double heldout_energy_error = 0;  // sum |V1 - V0| / sum V0 over the held-out samples
  int samples_attempted = 0;        // fine solves run
  int samples_dropped = 0;          // fine solves that did not converge
  int samples_coarse_inverted = 0;  // converged samples the coarse element cannot represent (det F <= 0)
  int samples_train = 0;
  int samples_heldout = 0;
  double seconds = 0;  // sampling + directions + fit

  explicit CoarseMaterialFit(int points = 8) { resize(points); }
  int points() const { return static_cast<int>(mu.size()); }
  void resize(int points);  // zero parameters, unit-x directions
};

// The per-point basis energies of V^1 for corner displacements u: a_k, b_k,
// s_k already multiplied by w_k det J_k, and the centre's a_c, b_c
// multiplied by V_e. With bubble modes in `coarse`, F_k includes
// `bubbles` A (A G_k^T; the centre has no bubble gradient). Returns false if
// the coarse element is inverted at a point or at its centre.
struct CoarseEnergyBasis {
  std::vector<double> a, b, s;
  double a_centre = 0, b_centre = 0;
};
bool coarse_energy_basis(const hex8::ElementGeometry& coarse, const hex8::NodeMatrix& X, const Vec24& u,
                         const std::vector<Vec3>& v, CoarseEnergyBasis& out, const Mat3& bubbles = Mat3::Zero());

// The Gauss-rule geometry of a coarse element X with `points` quadrature
// points (8 or 64), with bubble modes if `enhanced`: what a fit with that
// `enhanced` flag is evaluated on.
hex8::ElementGeometry coarse_fit_geometry(const hex8::NodeMatrix& X, int points, bool enhanced);

// V^1 of a fit at corner displacements u (+inf if inverted); for an
// enhanced fit the condensed energy min_A V^1(u, A). `coarse` must be
// coarse_fit_geometry(X, fit.points(), fit.enhanced) (std::invalid_argument
// if its bubble modes do not match the fit's).
double coarse_energy(const CoarseMaterialFit& fit, const hex8::ElementGeometry& coarse, const hex8::NodeMatrix& X,
                     const Vec24& u);

// True when the fit stores at least 1e-3 of the naive element's energy (the
// block's fine materials at their points, void points empty) under each
// small unit Voigt strain. A fit of a block with void children that fails
// this is not kept: a coarse element without stiffness in some uniform
// strain leaves its nodes free in that mode.
bool fit_resists_uniform_strains(const CoarseMaterialFit& fit, const FineBlock& block);

// Whole pipeline for one block: sampling, directions, fit. A block with a
// void child is fitted with periodic sampling (its spring direction from
// stiffest_periodic_direction); in the other modes it is returned with
// fitted = false, as is any block without usable samples or whose fit has
// no stiffness (the online coarsening falls back to naive coarsening).
CoarseMaterialFit fit_coarse_material(const FineBlock& block, const CoarseFitOptions& options);

// The fit on given samples and directions (C_k = 0 unless
// options.anisotropic). Lets callers compare models on identical samples.
CoarseMaterialFit fit_from_samples(const FineBlock& block, const ForceSampleSet& samples,
                                   const std::vector<Vec3>& directions, const CoarseFitOptions& options);

// Materials for a coarse element using the fit: per point MaterialSum of
// NeoHookean(mu_k, lambda_k) and AnisotropicSpring(C_k, v_k) (the spring is
// omitted where C_k = 0); where mu_c or lambda_c > 0, one more material,
// NeoHookean(mu_c, lambda_c), for the element centre (pair it with
// coarse_element_geometry). Throws std::invalid_argument if !fit.fitted.
QuadratureMaterials coarse_quadrature_materials(const CoarseMaterialFit& fit);

// The geometry that goes with `materials`: `gauss` itself, or `gauss` with
// the centre point of the element X when there is one material more than
// Gauss points.
hex8::ElementGeometry coarse_element_geometry(const hex8::ElementGeometry& gauss, const hex8::NodeMatrix& X,
                                              const QuadratureMaterials& materials);

}  // namespace msfab
