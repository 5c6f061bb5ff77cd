#include "gamut/continuous_refinement.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <nlopt.hpp>

#include "core/errors.hpp"
#include "homog/periodic_homogenization.hpp"

namespace msfab {
namespace {

int periodic_gap(int a, int b, int n) {
  const int d = std::abs(a - b);
  return std::min(d, n - d);
}

}  // namespace

struct ContinuousCellProblem::Evaluation {
  std::vector<double> x, xt;
  std::vector<double> xp, dxp;  // projected densities and dxp/dxt (xp = xt without projection)
  HomogenizationResult r;
  MatX C;  // the plane block (2D) or the 6 x 6 tensor
  double rho = 0;
  std::vector<Mat6> dC;  // per voxel: dC^H / d(x~^p), filled on demand
};

namespace {

void check_options(int nx, int ny, int nz, double h, const MaterialPtr& stiff, const ContinuousOptions& options) {
  if (nx < 2 || ny < 2 || nz < 1 || !(h > 0)) throw InputError("continuous step: the cell needs at least 2 x 2 voxels");
  if (!stiff) throw InputError("continuous step: no stiff material");
  if (options.max_iterations < 1 || !(options.penalty >= 1) || !(options.filter_radius >= 0) ||
      !(options.density_weight >= 0) || !(options.start_offset >= 0 && options.start_offset < 0.5) ||
      !(options.void_stiffness > 0) || !(options.projection_beta >= 0 && options.projection_beta <= 1024) ||
      options.min_feature < 1)
    throw InputError(
        "continuous step: need max_iterations >= 1, penalty >= 1, filter_radius >= 0, density_weight >= 0, "
        "0 <= start_offset < 0.5, void_stiffness > 0, 0 <= projection_beta <= 1024, min_feature >= 1");
  if (options.threshold_levels.empty()) throw InputError("continuous step: no threshold level");
  for (double level : options.threshold_levels)
    if (!(level > 0 && level < 1)) throw InputError("continuous step: threshold levels must lie in (0, 1)");
}

}  // namespace

ContinuousCellProblem::ContinuousCellProblem(int nx, int ny, int nz, double h, MaterialPtr stiff, MaterialPtr soft,
                                             const RefinementTarget& target, const ContinuousOptions& options)
    : nx_(nx), ny_(ny), nz_(nz), h_(h), target_(target), options_(options) {
  check_options(nx, ny, nz, h, stiff, options);
  const int m = nz == 1 ? 3 : 6;
  if (target.G.rows() != m || target.G.cols() != m || !target.G.allFinite())
    throw InputError("continuous step: the target G must be " + std::to_string(m) + " x " + std::to_string(m) +
                     (nz == 1 ? " (a 2D cell)" : " (a 3D cell)"));
  // W = G0^(-1/2): the misfit W (G - G0) W is relative per eigenmode of the
  // target, so a soft shear mode does not drown the Poisson coupling.
  const Eigen::SelfAdjointEigenSolver<MatX> eig(0.5 * (target.G + target.G.transpose()));
  if (eig.info() != Eigen::Success || !(eig.eigenvalues().minCoeff() > 0))
    throw InputError("continuous step: the target G is not positive definite");
  W_ = eig.eigenvectors() * eig.eigenvalues().cwiseInverse().cwiseSqrt().asDiagonal() * eig.eigenvectors().transpose();
  setup_cell(stiff, soft);
}

ContinuousCellProblem::ContinuousCellProblem(int nx, int ny, int nz, double h, MaterialPtr stiff, MaterialPtr soft,
                                             const MaterialSpace& space, const DirectedTarget& target,
                                             const ContinuousOptions& options)
    : nx_(nx), ny_(ny), nz_(nz), h_(h), space_(space), direction_(target.direction), options_(options) {
  check_options(nx, ny, nz, h, stiff, options);
  if ((space.kind() == MaterialSpaceKind::cubic3d) != (nz > 1))
    throw InputError("continuous step: a directed objective in a " +
                     std::string(nz > 1 ? "2D space on a 3D cell" : "3D space on a 2D cell"));
  const int n = space.dimension();
  if (target.direction.size() != n || !target.direction.allFinite() || !(target.direction.norm() > 0))
    throw InputError("continuous step: the direction needs " + std::to_string(n) + " finite entries, not all 0");
  if (target.floor.size() != 0 && target.floor.size() != n)
    throw InputError("continuous step: the floors need " + std::to_string(n) + " entries");
  for (int i = 0; i < target.floor.size(); ++i)
    if (target.floor[i] > 0) floors_.emplace_back(i, target.floor[i]);
  setup_cell(stiff, soft);
}

void ContinuousCellProblem::setup_cell(MaterialPtr stiff, MaterialPtr soft) {
  const int nx = nx_, ny = ny_, nz = nz_;  // short names for the index loops below
  const double h = h_;
  const ContinuousOptions& options = options_;
  K_stiff_ = voxel_stiffness(stiff, h);
  K_soft_ = soft ? voxel_stiffness(soft, h) : Mat24(options.void_stiffness * K_stiff_);

  // Orbits of the cell symmetry: one design variable each.
  VoxelGrid probe(nx, ny, nz, h);
  orbit_of_voxel_.assign(probe.size(), -1);
  std::map<std::size_t, int> orbit_of_fundamental;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const auto f = fundamental_voxel(probe, i, j, k, options.symmetry);
        const std::size_t key = probe.index(f[0], f[1], f[2]);
        auto [it, added] = orbit_of_fundamental.emplace(key, static_cast<int>(orbit_voxels_.size()));
        if (added) orbit_voxels_.emplace_back();
        orbit_of_voxel_[probe.index(i, j, k)] = it->second;
        orbit_voxels_[it->second].push_back(static_cast<int>(probe.index(i, j, k)));
      }

  if (!options.frozen_stiff.empty()) {
    if (options.frozen_stiff.size() != probe.size())
      throw InputError("continuous step: the frozen voxel mask has " + std::to_string(options.frozen_stiff.size()) +
                       " entries for " + std::to_string(probe.size()) + " voxels");
    frozen_orbit_.assign(orbit_voxels_.size(), 0);
    for (std::size_t o = 0; o < orbit_voxels_.size(); ++o) {
      int held = 0;
      for (int v : orbit_voxels_[o]) held += options.frozen_stiff[std::size_t(v)] != 0;
      if (held != 0 && held != int(orbit_voxels_[o].size()))
        throw InputError("continuous step: the frozen voxel mask does not have the cell's symmetry");
      frozen_orbit_[o] = held != 0;
    }
  }

  // Periodic cone filter, weights R - distance, normalized. The neighbours
  // of a voxel are offsets wrapped into the cell, so one stencil serves every
  // voxel; a small cell reaches one neighbour from two sides: merged.
  const double R = options.filter_radius;
  const int reach = R > 1 ? static_cast<int>(std::ceil(R)) : 0;
  const auto wrap = [](int d, int n) { return (d % n + n) % n; };
  std::map<std::array<int, 3>, std::size_t> tap_of_offset;
  double sum = 0;
  for (int dk = nz == 1 ? 0 : -reach; dk <= (nz == 1 ? 0 : reach); ++dk)
    for (int dj = -reach; dj <= reach; ++dj)
      for (int di = -reach; di <= reach; ++di) {
        const int a = wrap(di, nx), b = wrap(dj, ny), c = wrap(dk, nz);
        const double d = std::sqrt(double(periodic_gap(0, a, nx) * periodic_gap(0, a, nx) +
                                          periodic_gap(0, b, ny) * periodic_gap(0, b, ny) +
                                          periodic_gap(0, c, nz) * periodic_gap(0, c, nz)));
        const double w = reach == 0 ? (d == 0 ? 1.0 : 0.0) : std::max(0.0, R - d);
        if (w <= 0) continue;
        auto [it, added] = tap_of_offset.emplace(std::array<int, 3>{a, b, c}, filter_.size());
        if (added)
          filter_.push_back({a, b, c, w});
        else
          filter_[it->second].weight = std::max(filter_[it->second].weight, w);
      }
  for (const FilterTap& t : filter_) sum += t.weight;
  for (FilterTap& t : filter_) t.weight /= sum;
}

std::vector<double> ContinuousCellProblem::start(const VoxelGrid& structure, int stiff_id) const {
  if (structure.nx != nx_ || structure.ny != ny_ || structure.nz != nz_)
    throw InputError("continuous step: the structure's size differs from the problem's");
  std::vector<double> x(orbit_voxels_.size());
  for (std::size_t o = 0; o < x.size(); ++o) {
    double stiff = 0;  // majority over the orbit (one value for a symmetric structure)
    for (int v : orbit_voxels_[o]) stiff += structure.ids[v] == stiff_id;
    x[o] = frozen(int(o)) ? 1.0 : 0.5 + (2 * stiff >= orbit_voxels_[o].size() ? 1 : -1) * options_.start_offset;
  }
  return x;
}

// The smoothed Heaviside of Wang, Lazarov and Sigmund (2011) at eta = 0.5:
// beta -> infinity is the threshold at 0.5, beta = 0 the identity.
double ContinuousCellProblem::project(double xt, double* derivative) const {
  if (beta_ <= 0) {
    *derivative = 1;
    return xt;
  }
  const double eta = 0.5, denominator = std::tanh(beta_ * eta) + std::tanh(beta_ * (1 - eta));
  const double t = std::tanh(beta_ * (xt - eta));
  *derivative = beta_ * (1 - t * t) / denominator;
  return (std::tanh(beta_ * eta) + t) / denominator;
}

void ContinuousCellProblem::set_projection(double beta) {
  if (!(beta >= 0)) throw std::invalid_argument("ContinuousCellProblem::set_projection: beta < 0");
  beta_ = beta;
  last_.reset();
}

template <typename F>
void ContinuousCellProblem::for_each_filter_tap(F&& f) const {
  for (int k = 0; k < nz_; ++k)
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i) {
        const std::size_t v = std::size_t(i) + std::size_t(nx_) * (std::size_t(j) + std::size_t(ny_) * k);
        for (const FilterTap& t : filter_) {
          const int a = i + t.dx < nx_ ? i + t.dx : i + t.dx - nx_;
          const int b = j + t.dy < ny_ ? j + t.dy : j + t.dy - ny_;
          const int c = k + t.dz < nz_ ? k + t.dz : k + t.dz - nz_;
          f(v, std::size_t(a) + std::size_t(nx_) * (std::size_t(b) + std::size_t(ny_) * c), t.weight);
        }
      }
}

std::vector<double> ContinuousCellProblem::filtered(const std::vector<double>& x) const {
  std::vector<double> xt(orbit_of_voxel_.size(), 0.0);
  for_each_filter_tap([&](std::size_t v, std::size_t w, double weight) { xt[v] += weight * x[orbit_of_voxel_[w]]; });
  return xt;
}

void ContinuousCellProblem::homogenize_densities(Evaluation& e) const {
  VoxelStiffnessField field;
  field.nx = nx_, field.ny = ny_, field.nz = nz_, field.h = h_;
  field.basis = {K_soft_, K_stiff_ - K_soft_};
  field.weights.resize(2 * e.xp.size());
  for (std::size_t v = 0; v < e.xp.size(); ++v)
    field.weights[2 * v] = 1.0, field.weights[2 * v + 1] = std::pow(e.xp[v], options_.penalty);
  HomogenizationOptions solve;
  solve.use_symmetry = solve.use_mirror_symmetry = options_.use_symmetry;
  e.r = homogenize_elements(field, solve);
  const bool plane = nz_ == 1;
  const int m = plane ? 3 : 6;
  e.C.resize(m, m);
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b) e.C(a, b) = plane ? e.r.C(kPlaneVoigt[a], kPlaneVoigt[b]) : e.r.C(a, b);
  e.rho = 0;
  for (double t : e.xp) e.rho += t;
  e.rho /= e.xp.size();
}

ContinuousCellProblem::Evaluation ContinuousCellProblem::homogenize_structure(const VoxelGrid& structure,
                                                                              int stiff_id) const {
  if (structure.nx != nx_ || structure.ny != ny_ || structure.nz != nz_)
    throw InputError("continuous step: the structure's size differs from the problem's");
  Evaluation e;
  e.xp.resize(structure.ids.size());
  for (std::size_t v = 0; v < e.xp.size(); ++v) e.xp[v] = structure.ids[v] == stiff_id ? 1.0 : 0.0;
  homogenize_densities(e);
  return e;
}

VecX ContinuousCellProblem::structure_unit_properties(const VoxelGrid& structure, int stiff_id) const {
  if (!space_) throw std::logic_error("ContinuousCellProblem::structure_unit_properties: not a directed problem");
  return properties_and_gradients(homogenize_structure(structure, stiff_id), nullptr);
}

double ContinuousCellProblem::structure_objective(const VoxelGrid& structure, int stiff_id) const {
  if (space_) throw std::logic_error("ContinuousCellProblem::structure_objective: not a target problem");
  return target_objective(homogenize_structure(structure, stiff_id));
}

double ContinuousCellProblem::target_objective(const Evaluation& e) const {
  const MatX E = W_ * (e.C.inverse() - target_.G) * W_;
  return E.squaredNorm() + options_.density_weight * (e.rho - target_.rho) * (e.rho - target_.rho);
}

double ContinuousCellProblem::floor_violation(const VecX& u) const {
  double worst = 0;
  for (const auto& [i, floor] : floors_) worst = std::max(worst, floor - u[i]);
  return worst;
}

const ContinuousCellProblem::Evaluation& ContinuousCellProblem::evaluate(const std::vector<double>& x,
                                                                         bool with_sensitivities) const {
  if (!last_ || last_->x != x) {
    auto e = std::make_shared<Evaluation>();
    e->x = x;
    e->xt = filtered(x);
    e->xp.resize(e->xt.size());
    e->dxp.resize(e->xt.size());
    for (std::size_t v = 0; v < e->xt.size(); ++v) e->xp[v] = project(e->xt[v], &e->dxp[v]);
    // Frozen voxels are stiff whatever the filter does around them.
    for (std::size_t v = 0; v < options_.frozen_stiff.size(); ++v)
      if (options_.frozen_stiff[v]) e->xp[v] = 1.0, e->dxp[v] = 0.0;
    homogenize_densities(*e);
    last_ = std::move(e);
  }
  if (with_sensitivities && last_->dC.empty()) {
    // The fluctuations are stationary: dC^H/d(x~^p) = U_v^T (K_stiff - K_soft) U_v / |Y|.
    const Mat24 dK = K_stiff_ - K_soft_;
    const double volume = double(last_->xt.size()) * h_ * h_ * h_;
    std::vector<Mat6> dC(last_->xt.size());
#pragma omp parallel for schedule(static)
    for (std::int64_t v = 0; v < static_cast<std::int64_t>(dC.size()); ++v) {
      const Eigen::Matrix<double, 24, 6> U = total_element_displacements(last_->r, nx_, ny_, nz_, h_, v);
      dC[v] = U.transpose() * dK * U / volume;
    }
    last_->dC = std::move(dC);
  }
  return *last_;
}

void ContinuousCellProblem::chain(const Evaluation& e, const MatX& dfdC_small, double dfdrho,
                                  std::vector<double>* gradient) const {
  const bool plane = nz_ == 1;
  const int m = plane ? 3 : 6;
  Mat6 dfdC = Mat6::Zero();
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b) (plane ? dfdC(kPlaneVoigt[a], kPlaneVoigt[b]) : dfdC(a, b)) = dfdC_small(a, b);
  const double p = options_.penalty;
  const double drho = dfdrho / e.xt.size();
  std::vector<double> df_dxt(e.xt.size());
  for (std::size_t v = 0; v < e.xt.size(); ++v)
    df_dxt[v] = (p * std::pow(e.xp[v], p - 1) * (dfdC.cwiseProduct(e.dC[v])).sum() + drho) * e.dxp[v];
  // Through the filter (x~_v = sum_w H_vw x_orbit(w)) and the orbit sums.
  gradient->assign(orbit_voxels_.size(), 0.0);
  for_each_filter_tap(
      [&](std::size_t v, std::size_t w, double weight) { (*gradient)[orbit_of_voxel_[w]] += weight * df_dxt[v]; });
}

VecX ContinuousCellProblem::properties_and_gradients(const Evaluation& e, std::vector<MatX>* dudC) const {
  const VecX raw = space_->properties_with_gradient(e.C, e.rho, dudC);
  const VecX scale = space_->unit_derivative(raw);
  if (dudC)
    for (std::size_t i = 0; i < dudC->size(); ++i) (*dudC)[i] *= scale[static_cast<Eigen::Index>(i)];
  return space_->normalize(raw);
}

VecX ContinuousCellProblem::unit_properties(const std::vector<double>& x) const {
  if (!space_) throw std::logic_error("ContinuousCellProblem::unit_properties: not a directed problem");
  return properties_and_gradients(evaluate(x, false), nullptr);
}

double ContinuousCellProblem::objective(const std::vector<double>& x, std::vector<double>* gradient) const {
  const Evaluation& e = evaluate(x, gradient != nullptr);
  if (space_) {
    // f = -d . u; du_rho/drho = 1.
    std::vector<MatX> dudC;
    const VecX u = properties_and_gradients(e, gradient ? &dudC : nullptr);
    const double f = -direction_.dot(u);
    if (gradient) {
      MatX dfdC = MatX::Zero(e.C.rows(), e.C.cols());
      for (int i = 0; i + 1 < u.size(); ++i) dfdC -= direction_[i] * dudC[i];
      chain(e, dfdC, -direction_[u.size() - 1], gradient);
    }
    return f;
  }
  const MatX G = e.C.inverse();
  const MatX E = W_ * (G - target_.G) * W_;
  const double f = target_objective(e);
  // df/dG = 2 W E W; df/dC = -G (df/dG) G (all symmetric).
  if (gradient) chain(e, -2.0 * G * (W_ * E * W_) * G, 2.0 * options_.density_weight * (e.rho - target_.rho), gradient);
  return f;
}

double ContinuousCellProblem::constraint(int c, const std::vector<double>& x, std::vector<double>* gradient) const {
  if (c < 0 || c >= constraints()) throw std::out_of_range("ContinuousCellProblem::constraint");
  const auto [i, floor] = floors_[c];
  const Evaluation& e = evaluate(x, gradient != nullptr);
  std::vector<MatX> dudC;
  const VecX u = properties_and_gradients(e, gradient ? &dudC : nullptr);
  if (gradient) {
    if (i + 1 == u.size())
      chain(e, MatX::Zero(e.C.rows(), e.C.cols()), -1.0, gradient);
    else
      chain(e, -dudC[i], 0.0, gradient);
  }
  return floor - u[i];
}

VoxelGrid ContinuousCellProblem::threshold(const std::vector<double>& x, int stiff_id, int soft_id,
                                           double level) const {
  const std::vector<double> xt = filtered(x);
  VoxelGrid out(nx_, ny_, nz_, h_);
  for (std::size_t v = 0; v < xt.size(); ++v) out.ids[v] = xt[v] >= level ? stiff_id : soft_id;
  return out;
}

namespace {

// MMA from the structure's relaxed densities; the best iterate that meets
// the constraints (to 1e-3 in the unit cube) is thresholded, mirrored and
// cleaned.
ContinuousResult run_mma(ContinuousCellProblem& problem, const VoxelGrid& structure, int stiff_id, int soft_id,
                         const ContinuousOptions& options) {
  constexpr double kFeasible = 1e-3;
  std::vector<double> betas;  // continuation: 1, 2, 4, ... up to projection_beta
  for (double b = 1; options.projection_beta > 0 && b < options.projection_beta; b *= 2) betas.push_back(b);
  betas.push_back(options.projection_beta);
  const int stages = static_cast<int>(betas.size());

  std::vector<double> x = problem.start(structure, stiff_id);
  ContinuousResult result;
  // The best feasible iterate of the sharpest stage that has one: values
  // at different beta are different objectives.
  std::vector<double> best = x;
  double best_f = HUGE_VAL;
  struct Data {
    const ContinuousCellProblem* problem;
    ContinuousResult* result;
    std::vector<double> best;
    double best_f;
  } data{&problem, &result, {}, HUGE_VAL};
  auto objective = [](unsigned n, const double* xs, double* grad, void* raw) -> double {
    auto* d = static_cast<Data*>(raw);
    std::vector<double> xv(xs, xs + n), g;
    const double f = d->problem->objective(xv, grad ? &g : nullptr);
    if (grad) std::copy(g.begin(), g.end(), grad);
    d->result->history.push_back(f);
    bool feasible = true;
    for (int c = 0; c < d->problem->constraints(); ++c)
      feasible = feasible && d->problem->constraint(c, xv, nullptr) <= kFeasible;
    if (feasible && f < d->best_f) d->best_f = f, d->best = xv;
    return f;
  };
  auto constraint = [](unsigned n, const double* xs, double* grad, void* raw) -> double {
    auto* d = static_cast<std::pair<const ContinuousCellProblem*, int>*>(raw);
    std::vector<double> xv(xs, xs + n), g;
    const double c = d->first->constraint(d->second, xv, grad ? &g : nullptr);
    if (grad) std::copy(g.begin(), g.end(), grad);
    return c;
  };
  std::vector<std::pair<const ContinuousCellProblem*, int>> constraint_data;
  for (int c = 0; c < problem.constraints(); ++c) constraint_data.emplace_back(&problem, c);
  for (int stage = 0; stage < stages; ++stage) {
    problem.set_projection(betas[stage]);
    const int budget = options.max_iterations * (stage + 1) / stages - options.max_iterations * stage / stages;
    if (budget < 1) continue;
    nlopt::opt opt(nlopt::LD_MMA, static_cast<unsigned>(problem.variables()));
    std::vector<double> lower(std::size_t(problem.variables()), 0.0);
    for (int o = 0; o < problem.variables(); ++o) lower[std::size_t(o)] = problem.frozen(o) ? 1.0 : 0.0;
    opt.set_lower_bounds(lower);
    opt.set_upper_bounds(1.0);
    opt.set_min_objective(objective, &data);
    for (auto& c : constraint_data) opt.add_inequality_constraint(constraint, &c, 0.0);
    opt.set_maxeval(budget);
    opt.set_ftol_rel(1e-6);
    data.best.clear();
    data.best_f = HUGE_VAL;
    double f_final = 0;
    try {
      opt.optimize(x, f_final);
    } catch (const nlopt::roundoff_limited&) {
      // MMA stopped on round-off: the best iterate so far stands.
    } catch (const std::runtime_error& e) {
      throw NumericalError(std::string("continuous step: MMA failed: ") + e.what());
    }
    if (!data.best.empty()) best = data.best, best_f = data.best_f;
    // The next stage starts where this one ended (MMA's last iterate).
  }
  result.evaluations = static_cast<int>(result.history.size());
  result.start_objective = result.history.empty() ? 0 : result.history.front();
  result.best_objective = best_f;
  auto printable = [&](double level) {
    VoxelGrid g = problem.threshold(best, stiff_id, soft_id, level);
    mirror_fundamental_domain(g, options.symmetry);
    clean_structure(g);
    // The connector stays even where the structure does not reach it: it
    // joins the neighbour's.
    for (std::size_t v = 0; v < options.frozen_stiff.size(); ++v)
      if (options.frozen_stiff[v]) g.ids[v] = stiff_id;
    return g;
  };
  if (!problem.directed() && options.threshold_levels.size() == 1) {
    result.structure = printable(options.threshold_levels.front());
    result.threshold = options.threshold_levels.front();
  } else if (!problem.directed()) {
    // The level whose printable structure is closest to the target.
    double best_score = HUGE_VAL;
    result.structure = VoxelGrid(structure.nx, structure.ny, structure.nz, structure.voxel_size, soft_id);
    result.found = false;
    for (double level : options.threshold_levels) {
      VoxelGrid g = printable(level);
      if (g.count_solid() == 0 || thin_feature_voxels(g, options.min_feature) > 0) continue;
      const double score = problem.structure_objective(g, stiff_id);
      if (score < best_score)
        best_score = score, result.structure = std::move(g), result.threshold = level, result.found = true;
    }
  } else {
    // The grey optimum is not the printable one: face-disconnected pieces
    // (a one-node hinge carries load in the grey model) are cleaned away
    // and intermediate densities vanish. The threshold level whose cleaned
    // structure is best on the directed objective, floors met, is kept.
    double best_score = HUGE_VAL, best_violation = HUGE_VAL;
    result.structure = VoxelGrid(structure.nx, structure.ny, structure.nz, structure.voxel_size, soft_id);
    result.found = false;
    for (double level : {0.5, 0.3, 0.35, 0.4, 0.45, 0.55, 0.6, 0.65, 0.7}) {
      VoxelGrid g = printable(level);
      if (g.count_solid() == 0 || thin_feature_voxels(g, options.min_feature) > 0) continue;
      const VecX u = problem.structure_unit_properties(g, stiff_id);
      const double violation = problem.floor_violation(u), score = problem.directed_objective(u);
      const bool better =
          violation <= kFeasible ? (best_violation > kFeasible || score < best_score) : violation < best_violation;
      if (better) {
        best_score = score, best_violation = violation;
        result.structure = std::move(g), result.threshold = level, result.found = true;
      }
    }
  }
  return result;
}

}  // namespace

ContinuousResult refine_structure(const VoxelGrid& structure, int stiff_id, int soft_id, MaterialPtr stiff,
                                  MaterialPtr soft, const RefinementTarget& target, const ContinuousOptions& options) {
  ContinuousCellProblem problem(structure.nx, structure.ny, structure.nz, structure.voxel_size, stiff, soft, target,
                                options);
  return run_mma(problem, structure, stiff_id, soft_id, options);
}

ContinuousResult refine_structure_directed(const VoxelGrid& structure, int stiff_id, int soft_id, MaterialPtr stiff,
                                           MaterialPtr soft, const MaterialSpace& space, const DirectedTarget& target,
                                           const ContinuousOptions& options) {
  ContinuousCellProblem problem(structure.nx, structure.ny, structure.nz, structure.voxel_size, stiff, soft, space,
                                target, options);
  return run_mma(problem, structure, stiff_id, soft_id, options);
}

}  // namespace msfab
