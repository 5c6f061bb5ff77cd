#include "ddfem/coarse_fit.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <random>
#include <stdexcept>

#include "core/errors.hpp"
#include "ddfem/nnls.hpp"
#include "ddfem/periodic_samples.hpp"
#include "material/anisotropic_spring.hpp"
#include "material/material_sum.hpp"
#include "material/neo_hookean.hpp"

namespace msfab {
namespace {

// Deterministic held-out mask: a Fisher-Yates shuffle driven by the
// standardized mt19937_64 sequence; the first round(fraction * n) indices
// of the permutation are held out.
std::vector<char> heldout_mask(int n, double fraction, std::uint64_t seed) {
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[i] = i;
  std::mt19937_64 rng(seed);
  for (int i = n - 1; i > 0; --i) std::swap(order[i], order[rng() % std::uint64_t(i + 1)]);
  const int count = static_cast<int>(std::lround(fraction * n));
  std::vector<char> mask(n, 0);
  for (int i = 0; i < count; ++i) mask[order[i]] = 1;
  return mask;
}

// Weighted RMS; weights need not be normalized.
double weighted_rms(const std::vector<double>& rel, const std::vector<double>& weight) {
  double s = 0, w = 0;
  for (size_t i = 0; i < rel.size(); ++i) s += weight[i] * rel[i] * rel[i], w += weight[i];
  return w > 0 ? std::sqrt(s / w) : 0.0;
}

// Node positions of the coarse element X displaced by corner values u.
hex8::NodeMatrix deformed(const hex8::NodeMatrix& X, const Vec24& u) {
  hex8::NodeMatrix x = X;
  for (int n = 0; n < 8; ++n) x.row(n) += u.segment<3>(3 * n).transpose();
  return x;
}

}  // namespace

std::string fit_residual_name(CoarseFitOptions::Residual residual) {
  return residual == CoarseFitOptions::Residual::absolute ? "absolute" : "relative";
}

CoarseFitOptions::Residual parse_fit_residual(const std::string& name) {
  for (auto r : {CoarseFitOptions::Residual::relative, CoarseFitOptions::Residual::absolute})
    if (fit_residual_name(r) == name) return r;
  throw InputError("unknown fit residual '" + name + "' (relative or absolute)");
}

void CoarseMaterialFit::resize(int points) {
  mu.assign(points, 0.0), lambda.assign(points, 0.0), C.assign(points, 0.0);
  mu0.assign(points, 0.0), lambda0.assign(points, 0.0);
  v.assign(points, Vec3::UnitX());
}

bool coarse_energy_basis(const hex8::ElementGeometry& coarse, const hex8::NodeMatrix& X, const Vec24& u,
                         const std::vector<Vec3>& v, CoarseEnergyBasis& out, const Mat3& bubbles) {
  if (static_cast<int>(v.size()) != coarse.size())
    throw std::invalid_argument("coarse_energy_basis: one direction per quadrature point needed");
  auto F = coarse_deformation_gradients(coarse, X, u);
  if (coarse.has_enhanced_modes())
    for (int k = 0; k < coarse.size(); ++k) F[k].noalias() += bubbles * coarse.enhanced[k].transpose();
  const int points = coarse.size();
  out.a.resize(points), out.b.resize(points), out.s.resize(points);
  for (int k = 0; k < points; ++k) {
    const double J = F[k].determinant();
    if (!(J > 0.0)) return false;
    const double logJ = std::log(J);
    const double w = coarse.weight[k];
    out.a[k] = w * (0.5 * (F[k].squaredNorm() - 3.0) - logJ);
    out.b[k] = w * 0.5 * logJ * logJ;
    const double l = (F[k] * v[k]).norm();
    out.s[k] = w * (l - 1.0) * (l - 1.0);
  }
  const hex8::ElementGeometry centre = hex8::element_geometry(X, hex8::gauss_rule(1));
  const Mat3 Fc = hex8::deformation_gradient(deformed(X, u), centre.dNdX[0]);
  const double Jc = Fc.determinant();
  if (!(Jc > 0.0)) return false;
  const double logJc = std::log(Jc);
  out.a_centre = centre.weight[0] * (0.5 * (Fc.squaredNorm() - 3.0) - logJc);
  out.b_centre = centre.weight[0] * 0.5 * logJc * logJc;
  return true;
}

hex8::ElementGeometry coarse_fit_geometry(const hex8::NodeMatrix& X, int points, bool enhanced) {
  int per_axis = 1;
  while (per_axis * per_axis * per_axis < points) ++per_axis;
  if (per_axis * per_axis * per_axis != points)
    throw std::invalid_argument("coarse_fit_geometry: the point count must be a cube (8 or 64)");
  const hex8::QuadratureRule rule = hex8::gauss_rule(per_axis);
  return enhanced ? hex8::enhanced_element_geometry(X, rule) : hex8::element_geometry(X, rule);
}

namespace {

// The fit's materials whether or not it is marked fitted (the fit itself
// evaluates its intermediate parameters).
QuadratureMaterials fit_materials(const CoarseMaterialFit& fit) {
  QuadratureMaterials q;
  for (int k = 0; k < fit.points(); ++k) {
    MaterialPtr nh = NeoHookean::from_lame(fit.mu[k], fit.lambda[k]);
    if (fit.C[k] > 0.0)
      q.at_point.push_back(std::make_shared<MaterialSum>(
          std::vector<MaterialPtr>{nh, std::make_shared<AnisotropicSpring>(fit.C[k], fit.v[k])}));
    else
      q.at_point.push_back(nh);
  }
  if (fit.mu_centre > 0.0 || fit.lambda_centre > 0.0)
    q.at_point.push_back(NeoHookean::from_lame(fit.mu_centre, fit.lambda_centre));
  return q;
}

// Sample weights: kind weight / samples of that kind in the same split,
// normalized per split, so the data term is a weighted mean squared
// relative error.
std::vector<double> sample_weights(const std::vector<ForceKind>& kind, const std::vector<char>& held,
                                   const std::array<double, 5>& kind_weight, bool balance_kinds) {
  const int ns = static_cast<int>(kind.size());
  std::vector<double> weight(ns, 0.0);
  for (int split = 0; split < 2; ++split) {
    std::array<int, 5> count{};
    for (int s = 0; s < ns; ++s)
      if (held[s] == split) ++count[int(kind[s])];
    double total = 0;
    for (int s = 0; s < ns; ++s)
      if (held[s] == split) {
        weight[s] = kind_weight[int(kind[s])] / (balance_kinds ? count[int(kind[s])] : 1);
        total += weight[s];
      }
    for (int s = 0; s < ns; ++s)
      if (held[s] == split && total > 0) weight[s] /= total;
  }
  return weight;
}

// The fitted model's energies against the samples': the weighted RMS
// relative error of the training and the held-out samples, and the
// held-out energy error (sum of |differences| over sum of energies).
void record_fit_errors(const std::vector<CoarseEnergyBasis>& basis, const std::vector<double>& V0,
                       const std::vector<char>& held, const std::vector<double>& weight, CoarseMaterialFit& fit) {
  const int ns = static_cast<int>(V0.size());
  const int points = static_cast<int>(fit.mu.size());
  std::vector<double> rel_train, rel_held, w_train, w_held;
  double abs_held = 0, sum_held = 0;
  for (int s = 0; s < ns; ++s) {
    double V1 = fit.mu_centre * basis[s].a_centre + fit.lambda_centre * basis[s].b_centre;
    for (int k = 0; k < points; ++k)
      V1 += fit.mu[k] * basis[s].a[k] + fit.lambda[k] * basis[s].b[k] + fit.C[k] * basis[s].s[k];
    (held[s] ? rel_held : rel_train).push_back((V1 - V0[s]) / V0[s]);
    (held[s] ? w_held : w_train).push_back(weight[s]);
    if (held[s]) {
      abs_held += std::abs(V1 - V0[s]);
      sum_held += V0[s];
    }
  }
  fit.residual = weighted_rms(rel_train, w_train);
  fit.heldout_error = weighted_rms(rel_held, w_held);
  fit.heldout_energy_error = sum_held > 0 ? abs_held / sum_held : 0.0;
}

// The samples the coarse element can represent (not inverted, positive
// energy), with their energy bases at zero bubble amplitudes.
struct FitSamples {
  std::vector<CoarseEnergyBasis> basis;
  std::vector<double> V0;  // fine energies
  std::vector<ForceKind> kind;
  std::vector<const Vec24*> corners;  // coarse corner displacements, in `set`
};
FitSamples usable_samples(const ForceSampleSet& set, const hex8::ElementGeometry& coarse, const hex8::NodeMatrix& X,
                          CoarseMaterialFit& fit) {
  FitSamples out;
  for (const ForceSample& s : set.samples) {
    CoarseEnergyBasis e;
    if (!coarse_energy_basis(coarse, X, s.corner_displacement, fit.v, e) || !(s.energy > 0.0)) {
      ++fit.samples_coarse_inverted;
      continue;
    }
    out.basis.push_back(e);
    out.V0.push_back(s.energy);
    out.kind.push_back(set.patterns[s.pattern].kind);
    out.corners.push_back(&s.corner_displacement);
  }
  return out;
}

// The NNLS unknowns: mu, lambda (and C) per point, then the centre
// point's mu and lambda if fitted; each column's scale and the scaled
// regularization target p^0 / scale.
struct ParameterColumns {
  int per_point = 2, centre = 0, count = 0;  // centre: mu_c's column, then lambda_c's
  VecX scale, target;
};
ParameterColumns parameter_columns(const CoarseMaterialFit& fit, const CoarseFitOptions& options) {
  const int points = static_cast<int>(fit.mu0.size());
  ParameterColumns c;
  c.per_point = options.anisotropic ? 3 : 2;
  c.centre = points * c.per_point;
  c.count = c.centre + (options.centre_point ? 2 : 0);
  const int per_point = c.per_point, centre = c.centre, np = c.count;
  // Unknowns per point: mu, lambda (and C). Columns are scaled by the
  // block's volume-averaged fine parameters (mean mu for mu and C, mean
  // lambda for lambda), so scaled unknowns are O(1) and the regularizer of
  // Eq. 2.9 measures every deviation in the same units. A per-point scale
  // would forbid a soft point from stiffening, yet in a layered block the
  // soft children's points must carry the stiff layer's in-plane stiffness.
  double mu_mean = 0, lambda_mean = 0;
  for (int k = 0; k < points; ++k) mu_mean += fit.mu0[k] / points, lambda_mean += fit.lambda0[k] / points;
  if (!(lambda_mean > 1e-6 * mu_mean)) lambda_mean = mu_mean;
  VecX& scale = c.scale;
  VecX& target = c.target;
  scale.resize(np);
  target.resize(np);
  for (int k = 0; k < points; ++k) {
    scale[per_point * k] = mu_mean;
    target[per_point * k] = fit.mu0[k] / mu_mean;
    scale[per_point * k + 1] = lambda_mean;
    target[per_point * k + 1] = fit.lambda0[k] / lambda_mean;
    if (options.anisotropic) {
      scale[per_point * k + 2] = mu_mean;
      target[per_point * k + 2] = 0.0;
    }
  }
  // The centre starts from nothing: the fine block's material is at the
  // Gauss points (p^0), and the data move stiffness to the centre where
  // bending samples ask for it.
  if (options.centre_point) {
    scale[centre] = mu_mean, target[centre] = 0.0;
    scale[centre + 1] = lambda_mean, target[centre + 1] = 0.0;
  }
  return c;
}

}  // namespace

double coarse_energy(const CoarseMaterialFit& fit, const hex8::ElementGeometry& coarse, const hex8::NodeMatrix& X,
                     const Vec24& u) {
  CoarseEnergyBasis e;
  if (fit.points() != coarse.size())
    throw std::invalid_argument("coarse_energy: the fit and the geometry have different point counts");
  if (fit.enhanced != coarse.has_enhanced_modes())
    throw std::invalid_argument("coarse_energy: the geometry's bubble modes do not match the fit's element");
  Mat3 A = Mat3::Zero();
  if (fit.enhanced) {
    const QuadratureMaterials m = fit_materials(fit);
    if (!hex_condensed_bubbles(coarse_element_geometry(coarse, X, m), m, deformed(X, u), A)) return kInfiniteEnergy;
  }
  if (!coarse_energy_basis(coarse, X, u, fit.v, e, A)) return kInfiniteEnergy;
  double V = 0;
  for (int k = 0; k < fit.points(); ++k) V += fit.mu[k] * e.a[k] + fit.lambda[k] * e.b[k] + fit.C[k] * e.s[k];
  return V + fit.mu_centre * e.a_centre + fit.lambda_centre * e.b_centre;
}

// The fitted element stores at least 1e-3 of the naive element's energy
// (the fine materials at their points, void points empty) under each unit
// Voigt strain.
bool fit_resists_uniform_strains(const CoarseMaterialFit& fit, const FineBlock& block) {
  CoarseMaterialFit naive = fit;
  for (int k = 0; k < fit.points(); ++k) naive.mu[k] = fit.mu0[k], naive.lambda[k] = fit.lambda0[k], naive.C[k] = 0.0;
  naive.mu_centre = naive.lambda_centre = 0.0;
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  const hex8::ElementGeometry geo = coarse_fit_geometry(X, fit.points(), fit.enhanced);
  constexpr int kVoigt[6][2] = {{0, 0}, {1, 1}, {2, 2}, {1, 2}, {0, 2}, {0, 1}};  // xx yy zz yz xz xy
  for (const auto& [a, b] : kVoigt) {
    Mat3 eps = Mat3::Zero();
    eps(a, b) = eps(b, a) = 1e-3;
    Vec24 u;
    for (int c = 0; c < 8; ++c) u.segment<3>(3 * c) = eps * X.row(c).transpose();
    if (!(coarse_energy(fit, geo, X, u) >= 1e-3 * coarse_energy(naive, geo, X, u))) return false;
  }
  return true;
}

namespace {

// Enhanced element: the samples' basis at the bubble amplitudes that the
// fit's current parameters choose, sample by sample (a sample whose
// condensed state cannot be evaluated keeps its previous amplitudes).
void update_bubble_basis(const hex8::ElementGeometry& coarse, const hex8::NodeMatrix& X, const CoarseMaterialFit& fit,
                         FitSamples& samples) {
  const QuadratureMaterials m = fit_materials(fit);
  const hex8::ElementGeometry geo = coarse_element_geometry(coarse, X, m);
  for (size_t s = 0; s < samples.basis.size(); ++s) {
    Mat3 A;
    CoarseEnergyBasis e;
    if (!hex_condensed_bubbles(geo, m, deformed(X, *samples.corners[s]), A)) continue;
    if (!coarse_energy_basis(coarse, X, *samples.corners[s], fit.v, e, A)) continue;
    samples.basis[s] = e;
  }
}

// The least-squares system of Eq. 2.9. Data rows: each training sample's
// residual relative to its own energy (or to the block's RMS training
// energy, `energy_ref` > 0, for the absolute residual), times sqrt(weight);
// then the regularizer's rows sqrt(reg) * (p_j - p0_j) / scale_j, which
// fill_data_rows leaves alone.
struct FitSystem {
  MatX A;
  VecX b;
  double energy_ref = 0;  // 0: residuals relative to each sample's energy
};
int fill_data_rows(const FitSamples& samples, const std::vector<char>& held, const std::vector<double>& weight,
                   const ParameterColumns& columns, const CoarseFitOptions& options, FitSystem& system) {
  const int per_point = columns.per_point, centre = columns.centre;
  const int points = centre / per_point;  // the point columns come first
  const VecX& scale = columns.scale;
  int r = 0;
  for (int s = 0; s < static_cast<int>(samples.V0.size()); ++s) {
    if (held[s]) continue;
    const CoarseEnergyBasis& e = samples.basis[s];
    const double w = std::sqrt(weight[s]) / (system.energy_ref > 0 ? system.energy_ref : samples.V0[s]);
    for (int k = 0; k < points; ++k) {
      system.A(r, per_point * k) = w * e.a[k] * scale[per_point * k];
      system.A(r, per_point * k + 1) = w * e.b[k] * scale[per_point * k + 1];
      if (options.anisotropic) system.A(r, per_point * k + 2) = w * e.s[k] * scale[per_point * k + 2];
    }
    if (options.centre_point) {
      system.A(r, centre) = w * e.a_centre * scale[centre];
      system.A(r, centre + 1) = w * e.b_centre * scale[centre + 1];
    }
    system.b[r] = w * samples.V0[s];
    ++r;
  }
  return r;
}

// The NNLS solution's scaled columns back into the fit's parameters.
void unpack_parameters(const NnlsResult& x, const ParameterColumns& columns, const CoarseFitOptions& options,
                       CoarseMaterialFit& fit) {
  const int per_point = columns.per_point, centre = columns.centre;
  const VecX& scale = columns.scale;
  for (int k = 0; k < fit.points(); ++k) {
    fit.mu[k] = x.x[per_point * k] * scale[per_point * k];
    fit.lambda[k] = x.x[per_point * k + 1] * scale[per_point * k + 1];
    fit.C[k] = options.anisotropic ? x.x[per_point * k + 2] * scale[per_point * k + 2] : 0.0;
  }
  if (options.centre_point) {
    fit.mu_centre = x.x[centre] * scale[centre];
    fit.lambda_centre = x.x[centre + 1] * scale[centre + 1];
  }
}

// Sample weights: kind weight / samples of that kind in the same split,
// normalized per split, so the data term is a weighted mean squared
// relative error; a mixed block may keep only its affine samples.
std::vector<double> block_sample_weights(const FineBlock& block, const std::vector<ForceKind>& kind,
                                         const std::vector<char>& held, const CoarseFitOptions& options) {
  for (double w : options.kind_weight)
    if (!(w >= 0.0) || !std::isfinite(w)) throw InputError("coarse fit: kind weights must be finite and >= 0");
  std::array<double, 5> kind_weight = options.kind_weight;
  const bool uniform = std::all_of(block.material_ids.begin(), block.material_ids.end(),
                                   [&](int id) { return id != 0 && id == block.material_ids[0]; });
  if (options.mixed_blocks_affine_only && !uniform)
    for (ForceKind k : {ForceKind::bend, ForceKind::twist, ForceKind::pinch}) kind_weight[int(k)] = 0.0;
  return sample_weights(kind, held, kind_weight, options.balance_kinds);
}

}  // namespace

CoarseMaterialFit fit_from_samples(const FineBlock& block, const ForceSampleSet& set,
                                   const std::vector<Vec3>& directions, const CoarseFitOptions& options) {
  if (!(options.regularization >= 0.0)) throw InputError("coarse fit: regularization must be >= 0");
  if (!(options.heldout_fraction >= 0.0 && options.heldout_fraction < 1.0))
    throw InputError("coarse fit: heldout_fraction must be in [0, 1)");
  const auto t0 = std::chrono::steady_clock::now();
  const int points = block.coarse_points();
  if (static_cast<int>(directions.size()) != points)
    throw std::invalid_argument("fit_from_samples: one direction per coarse quadrature point needed");
  CoarseMaterialFit fit(points);
  fit.material_ids = block.material_ids;
  fit.samples_attempted = set.attempted;
  fit.samples_dropped = set.dropped;
  for (int k = 0; k < points; ++k) {
    fit.v[k] = directions[k].normalized();
    fit.mu0[k] = block.point_mu0[k];
    fit.lambda0[k] = block.point_lambda0[k];
  }
  // Basis energies of the samples the coarse element can represent.
  const hex8::NodeMatrix X = block.coarse_rest_positions();
  const hex8::ElementGeometry coarse = coarse_fit_geometry(X, points, options.enhanced_element);
  fit.enhanced = options.enhanced_element;
  FitSamples samples = usable_samples(set, coarse, X, fit);
  const std::vector<double>& V0 = samples.V0;
  auto update_bubbles = [&]() { update_bubble_basis(coarse, X, fit, samples); };
  if (options.enhanced_element) {
    // Start from the fine materials at their points, as the regularizer does.
    for (int k = 0; k < points; ++k) fit.mu[k] = fit.mu0[k], fit.lambda[k] = fit.lambda0[k];
    update_bubbles();
  }
  const int ns = static_cast<int>(V0.size());
  const std::vector<char> held = heldout_mask(ns, options.heldout_fraction, options.split_seed);
  for (char h : held) (h ? fit.samples_heldout : fit.samples_train) += 1;
  if (fit.samples_train < 4) {
    fit.not_fitted_reason = "fewer than 4 usable training samples";
    return fit;
  }

  const ParameterColumns columns = parameter_columns(fit, options);
  const int np = columns.count;
  const std::vector<double> weight = block_sample_weights(block, samples.kind, held, options);

  FitSystem system;
  if (options.residual == CoarseFitOptions::Residual::absolute) {
    for (int s = 0; s < ns; ++s)
      if (!held[s]) system.energy_ref += weight[s] * V0[s] * V0[s];
    system.energy_ref = std::sqrt(system.energy_ref);
    if (!(system.energy_ref > 0)) {
      fit.not_fitted_reason = "no training sample has a weight";
      return fit;
    }
  }
  const int rows = fit.samples_train + np;
  system.A = MatX::Zero(rows, np);
  system.b = VecX::Zero(rows);
  int r = fill_data_rows(samples, held, weight, columns, options, system);
  // lambda is Eq. 2.9's for the 8 points of a level-1 element; with more
  // points (64 at level 2) each weighs 8 / points, so the regularizer's pull
  // on a uniform relative change of the material is the same at every level.
  const double reg = std::sqrt(options.regularization * 8.0 / points);
  for (int j = 0; j < np; ++j, ++r) {
    system.A(r, j) = reg;
    system.b[r] = reg * columns.target[j];
  }
  NnlsResult sol = solve_nnls(system.A, system.b);
  if (sol.converged) unpack_parameters(sol, columns, options, fit);
  // Enhanced element: alternate bubbles for the parameters and parameters
  // for the bubbles until the scaled parameters move less than 1e-3. The
  // basis left behind is always that of the final parameters' own bubbles,
  // so the errors below are those of the element used online.
  if (options.enhanced_element && sol.converged) {
    for (fit.bubble_rounds = 1;; ++fit.bubble_rounds) {
      update_bubbles();
      if (fit.bubble_rounds >= options.bubble_rounds) break;
      fill_data_rows(samples, held, weight, columns, options, system);
      const NnlsResult next = solve_nnls(system.A, system.b);
      if (!next.converged) break;
      const double moved = (next.x - sol.x).cwiseAbs().maxCoeff();
      sol = next;
      unpack_parameters(sol, columns, options, fit);
      if (moved <= 1e-3 * std::max(1.0, sol.x.cwiseAbs().maxCoeff())) {
        update_bubbles();
        break;
      }
    }
  }
  if (!sol.converged) {
    fit.not_fitted_reason = "NNLS did not converge";
    return fit;
  }
  // A block whose samples all cost (almost) nothing, e.g. void children
  // that leave the solid ones hinged, fits to no stiffness at all: a coarse
  // element without energy would leave its nodes free in a coarse mesh.
  if (!(sol.x.maxCoeff() > 0.0)) {
    fit.not_fitted_reason = "the fit has no stiffness";
    return fit;
  }
  fit.fitted = true;
  fit.objective = sol.residual * sol.residual;
  if (!block.all_children_solid() && !fit_resists_uniform_strains(fit, block)) {
    // Fitted to the samples of a block that is nearly a mechanism among its
    // copies (children hinged at edges, void layers), the element can lose
    // all stiffness in some uniform strain: in a coarse mesh its nodes
    // would be free in that mode, and a Newton solve fails. Naive
    // coarsening, stiff where the children are solid, is the safe choice.
    fit.fitted = false;
    fit.not_fitted_reason = "the fit has (almost) no stiffness in a uniform strain";
    return fit;
  }

  record_fit_errors(samples.basis, V0, held, weight, fit);
  fit.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return fit;
}

CoarseMaterialFit fit_coarse_material(const FineBlock& block, const CoarseFitOptions& options) {
  const bool periodic = options.sampling.mode == ForceSamplingOptions::Mode::periodic;
  if (block.voxels_per_edge != 2 && !periodic)
    throw InputError("coarse fit: a block of " + std::to_string(block.voxels_per_edge) +
                     "^3 voxels is sampled among periodic copies only (sampling.mode: periodic)");
  // Isolated and patch samples load the block's own nodes: a void child
  // leaves a coarse corner without a fine node there.
  if (!periodic && (!block.all_children_solid() || !block.has_all_corners())) {
    CoarseMaterialFit fit(block.coarse_points());
    fit.material_ids = block.material_ids;
    fit.not_fitted_reason = "a child of the block is void (fitted with periodic sampling only)";
    return fit;
  }
  const auto t0 = std::chrono::steady_clock::now();
  // A block of more voxels costs more per sample: it is sampled in the
  // kinds its fit weighs only (the level-1 blocks, as they were built, in all).
  ForceSamplingOptions sampling = options.sampling;
  if (block.voxels_per_edge != 2)
    for (int k = 0; k < 5; ++k) sampling.kinds[k] = options.kind_weight[k] > 0;
  const ForceSampleSet samples = periodic ? sample_periodic(block, sampling) : sample_force_space(block, sampling);
  std::vector<Vec3> directions(block.coarse_points(), Vec3::UnitX());
  if (options.anisotropic) {
    if (block.voxels_per_edge != 2) {
      directions = periodic_point_directions(block, options.anisotropy);
    } else if (block.all_children_solid()) {
      directions = estimate_anisotropy(block, options.anisotropy).direction;
    } else {
      const AnisotropyOptions& a = options.anisotropy;
      directions.assign(block.coarse_points(),
                        stiffest_periodic_direction(block, a.directions, a.strain, a.seed, a.newton_tolerance));
    }
  }
  CoarseMaterialFit fit = fit_from_samples(block, samples, directions, options);
  fit.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return fit;
}

QuadratureMaterials coarse_quadrature_materials(const CoarseMaterialFit& fit) {
  if (!fit.fitted) throw std::invalid_argument("coarse_quadrature_materials: the block was not fitted");
  return fit_materials(fit);
}

hex8::ElementGeometry coarse_element_geometry(const hex8::ElementGeometry& gauss, const hex8::NodeMatrix& X,
                                              const QuadratureMaterials& materials) {
  const int n = static_cast<int>(materials.at_point.size());
  if (n == gauss.size() + 1) return hex8::with_centre_point(gauss, X);
  return gauss;
}

}  // namespace msfab
