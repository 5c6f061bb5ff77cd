#include "gamut/continuous_refinement.hpp"

#include <nlopt.hpp>

#include <algorithm>
#include <cmath>
#include <map>

#include "core/errors.hpp"
#include "homog/periodic_homogenization.hpp"

namespace msfab {
namespace {

int periodic_gap(int a, int b, int n) {
  const int d = std::abs(a - b);
  return std::min(d, n - d);
}

}  // namespace

ContinuousCellProblem::ContinuousCellProblem(int nx, int ny, int nz, double h, MaterialPtr stiff, MaterialPtr soft,
                                             const RefinementTarget& target, const ContinuousOptions& options)
    : nx_(nx), ny_(ny), nz_(nz), h_(h), target_(target), options_(options) {
  if (nx < 2 || ny < 2 || nz < 1 || !(h > 0)) throw InputError("continuous step: the cell needs at least 2 x 2 voxels");
  if (!stiff) throw InputError("continuous step: no stiff material");
  if (options.max_iterations < 1 || !(options.penalty >= 1) || !(options.filter_radius >= 0) ||
      !(options.density_weight >= 0) || !(options.start_offset >= 0 && options.start_offset < 0.5) ||
      !(options.void_stiffness > 0))
    throw InputError(
        "continuous step: need max_iterations >= 1, penalty >= 1, filter_radius >= 0, density_weight >= 0, "
        "0 <= start_offset < 0.5, void_stiffness > 0");
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

  // Periodic cone filter, weights R - distance, rows normalized.
  const double R = options.filter_radius;
  const int reach = R > 1 ? static_cast<int>(std::ceil(R)) : 0;
  filter_.resize(probe.size());
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        auto& row = filter_[probe.index(i, j, k)];
        double sum = 0;
        for (int dk = nz == 1 ? 0 : -reach; dk <= (nz == 1 ? 0 : reach); ++dk)
          for (int dj = -reach; dj <= reach; ++dj)
            for (int di = -reach; di <= reach; ++di) {
              const int a = ((i + di) % nx + nx) % nx, b = ((j + dj) % ny + ny) % ny, c = ((k + dk) % nz + nz) % nz;
              const double d = std::sqrt(double(periodic_gap(i, a, nx) * periodic_gap(i, a, nx) +
                                                periodic_gap(j, b, ny) * periodic_gap(j, b, ny) +
                                                periodic_gap(k, c, nz) * periodic_gap(k, c, nz)));
              const double w = reach == 0 ? (d == 0 ? 1.0 : 0.0) : std::max(0.0, R - d);
              if (w <= 0) continue;
              const int v = static_cast<int>(probe.index(a, b, c));
              // A small cell can reach one neighbour from two sides: merge.
              auto it = std::find_if(row.begin(), row.end(), [&](const auto& e) { return e.first == v; });
              if (it == row.end()) row.emplace_back(v, w);
              else it->second = std::max(it->second, w);
            }
        for (const auto& e : row) sum += e.second;
        for (auto& e : row) e.second /= sum;
      }
}

std::vector<double> ContinuousCellProblem::start(const VoxelGrid& structure, int stiff_id) const {
  if (structure.nx != nx_ || structure.ny != ny_ || structure.nz != nz_)
    throw InputError("continuous step: the structure's size differs from the problem's");
  std::vector<double> x(orbit_voxels_.size());
  for (std::size_t o = 0; o < x.size(); ++o) {
    double stiff = 0;  // majority over the orbit (one value for a symmetric structure)
    for (int v : orbit_voxels_[o]) stiff += structure.ids[v] == stiff_id;
    x[o] = 0.5 + (2 * stiff >= orbit_voxels_[o].size() ? 1 : -1) * options_.start_offset;
  }
  return x;
}

std::vector<double> ContinuousCellProblem::filtered(const std::vector<double>& x) const {
  std::vector<double> xt(filter_.size(), 0.0);
  for (std::size_t v = 0; v < filter_.size(); ++v)
    for (const auto& [w, weight] : filter_[v]) xt[v] += weight * x[orbit_of_voxel_[w]];
  return xt;
}

double ContinuousCellProblem::objective(const std::vector<double>& x, std::vector<double>* gradient) const {
  const std::vector<double> xt = filtered(x);
  const double p = options_.penalty;
  const Mat24 dK = K_stiff_ - K_soft_;
  VoxelStiffnessField field;
  field.nx = nx_, field.ny = ny_, field.nz = nz_, field.h = h_;
  field.basis = {K_soft_, dK};
  field.weights.resize(2 * xt.size());
  for (std::size_t v = 0; v < xt.size(); ++v) field.weights[2 * v] = 1.0, field.weights[2 * v + 1] = std::pow(xt[v], p);
  const HomogenizationResult r = homogenize_elements(field);
  const bool plane = nz_ == 1;
  const int m = plane ? 3 : 6;
  MatX C(m, m);
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b) C(a, b) = plane ? r.C(kPlaneVoigt[a], kPlaneVoigt[b]) : r.C(a, b);
  const MatX G = C.inverse();
  const MatX E = W_ * (G - target_.G) * W_;
  double rho = 0;
  for (double t : xt) rho += t;
  rho /= xt.size();
  const double f = E.squaredNorm() + options_.density_weight * (rho - target_.rho) * (rho - target_.rho);
  if (!gradient) return f;

  // df/dG = 2 W E W; df/dC = -G (df/dG) G (all symmetric), embedded in the 6 x 6 Voigt block.
  const MatX dfdC_small = -2.0 * G * (W_ * E * W_) * G;
  Mat6 dfdC = Mat6::Zero();
  for (int a = 0; a < m; ++a)
    for (int b = 0; b < m; ++b) (plane ? dfdC(kPlaneVoigt[a], kPlaneVoigt[b]) : dfdC(a, b)) = dfdC_small(a, b);
  const double volume = double(xt.size()) * h_ * h_ * h_;
  const double drho = 2.0 * options_.density_weight * (rho - target_.rho) / xt.size();
  std::vector<double> df_dxt(xt.size());
#pragma omp parallel for schedule(static)
  for (std::int64_t v = 0; v < static_cast<std::int64_t>(xt.size()); ++v) {
    const Eigen::Matrix<double, 24, 6> U = total_element_displacements(r, nx_, ny_, nz_, h_, v);
    const Mat6 dC = U.transpose() * dK * U / volume;  // dC / d(x~^p)
    df_dxt[v] = p * std::pow(xt[v], p - 1) * (dfdC.cwiseProduct(dC)).sum() + drho;
  }
  // Through the filter (x~_v = sum_w H_vw x_orbit(w)) and the orbit sums.
  gradient->assign(orbit_voxels_.size(), 0.0);
  for (std::size_t v = 0; v < filter_.size(); ++v)
    for (const auto& [w, weight] : filter_[v]) (*gradient)[orbit_of_voxel_[w]] += weight * df_dxt[v];
  return f;
}

VoxelGrid ContinuousCellProblem::threshold(const std::vector<double>& x, int stiff_id, int soft_id) const {
  const std::vector<double> xt = filtered(x);
  VoxelGrid out(nx_, ny_, nz_, h_);
  for (std::size_t v = 0; v < xt.size(); ++v) out.ids[v] = xt[v] >= 0.5 ? stiff_id : soft_id;
  return out;
}

ContinuousResult refine_structure(const VoxelGrid& structure, int stiff_id, int soft_id, MaterialPtr stiff,
                                  MaterialPtr soft, const RefinementTarget& target, const ContinuousOptions& options) {
  const ContinuousCellProblem problem(structure.nx, structure.ny, structure.nz, structure.voxel_size, stiff, soft,
                                      target, options);
  std::vector<double> x = problem.start(structure, stiff_id);
  ContinuousResult result;
  std::vector<double> best = x;
  double best_f = HUGE_VAL;
  struct Data {
    const ContinuousCellProblem* problem;
    ContinuousResult* result;
    std::vector<double>* best;
    double* best_f;
  } data{&problem, &result, &best, &best_f};
  auto callback = [](unsigned n, const double* xs, double* grad, void* raw) -> double {
    auto* d = static_cast<Data*>(raw);
    std::vector<double> xv(xs, xs + n), g;
    const double f = d->problem->objective(xv, grad ? &g : nullptr);
    if (grad) std::copy(g.begin(), g.end(), grad);
    d->result->history.push_back(f);
    if (f < *d->best_f) *d->best_f = f, *d->best = xv;
    return f;
  };
  nlopt::opt opt(nlopt::LD_MMA, static_cast<unsigned>(problem.variables()));
  opt.set_lower_bounds(0.0);
  opt.set_upper_bounds(1.0);
  opt.set_min_objective(callback, &data);
  opt.set_maxeval(options.max_iterations);
  opt.set_ftol_rel(1e-6);
  double f_final = 0;
  try {
    opt.optimize(x, f_final);
  } catch (const nlopt::roundoff_limited&) {
    // MMA stopped on round-off: the best iterate so far stands.
  } catch (const std::runtime_error& e) {
    throw NumericalError(std::string("continuous step: MMA failed: ") + e.what());
  }
  result.evaluations = static_cast<int>(result.history.size());
  result.start_objective = result.history.empty() ? 0 : result.history.front();
  result.best_objective = best_f;
  result.structure = problem.threshold(best, stiff_id, soft_id);
  mirror_fundamental_domain(result.structure, options.symmetry);
  clean_structure(result.structure);
  return result;
}

}  // namespace msfab
