#include "families/gaussian_mixture.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "core/errors.hpp"

namespace msfab {
namespace {

constexpr double kLog2Pi = 1.8378770664093454836;

// Uniform in [0, 1) from the top 53 bits of the raw engine output: the
// standard distributions are implementation-defined, this is not.
double uniform01(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

// Decorrelates the seeds of neighbouring starts (splitmix64 finalizer).
std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t start) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ull * (start + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

MatX covariance_of(const MatX& X) {
  const MatX centred = X.rowwise() - X.colwise().mean();
  return centred.transpose() * centred / double(X.rows());
}

struct Model {
  VecX weights;
  MatX means;
  std::vector<MatX> covs;
};

// ln(w_k N(x_i; mu_k, Sigma_k)) for every point and component. False when
// a covariance is not positive definite.
bool log_densities(const Model& m, const MatX& X, MatX& logp) {
  const int n = static_cast<int>(X.rows()), d = static_cast<int>(X.cols()), K = static_cast<int>(m.means.rows());
  logp.resize(n, K);
  for (int k = 0; k < K; ++k) {
    const Eigen::LLT<MatX> llt(m.covs[k]);
    if (llt.info() != Eigen::Success) return false;
    const double logdet = 2.0 * llt.matrixLLT().diagonal().array().log().sum();
    const double logw = m.weights[k] > 0 ? std::log(m.weights[k]) : -std::numeric_limits<double>::infinity();
    MatX centred = (X.rowwise() - m.means.row(k)).transpose();  // d x n
    llt.matrixL().solveInPlace(centred);
    const VecX maha = centred.colwise().squaredNorm().transpose();
    logp.col(k) = (logw - 0.5 * (d * kLog2Pi + logdet)) - 0.5 * maha.array();
  }
  return true;
}

// Turns log densities into responsibilities in place; returns sum_i ln p(x_i).
double normalize_responsibilities(MatX& logp) {
  double total = 0.0;
  for (Eigen::Index i = 0; i < logp.rows(); ++i) {
    const double top = logp.row(i).maxCoeff();
    const double lse = top + std::log((logp.row(i).array() - top).exp().sum());
    logp.row(i) = (logp.row(i).array() - lse).exp();
    total += lse;
  }
  return total;
}

// One M-step from responsibilities R. A component with (numerically) no
// points keeps its previous mean and covariance.
void maximize(const MatX& X, const MatX& R, double opt_reg, double trace_floor, double variance_floor, Model& m) {
  const int n = static_cast<int>(X.rows()), d = static_cast<int>(X.cols()), K = static_cast<int>(R.cols());
  for (int k = 0; k < K; ++k) {
    const double nk = R.col(k).sum();
    m.weights[k] = nk / n;
    if (!(nk > 1e-8)) continue;
    m.means.row(k) = (R.col(k).transpose() * X) / nk;
    const MatX centred = X.rowwise() - m.means.row(k);
    MatX S = centred.transpose() * R.col(k).asDiagonal() * centred / nk;
    S = 0.5 * (S + S.transpose());
    S.diagonal().array() += opt_reg * std::max(S.trace(), trace_floor) / d + variance_floor;
    m.covs[k] = S;
  }
  m.weights /= m.weights.sum();
}

struct Run {
  bool ok = false;
  Model model;
  MatX resp;
  double logL = -std::numeric_limits<double>::infinity();
  int iterations = 0;
  bool converged = false;
  std::vector<double> history;
};

// k-means++ centres, hard assignment to the nearest, then EM.
Run run_em(const MatX& X, const GmmOptions& o, int start, double trace_floor, double variance_floor) {
  const int n = static_cast<int>(X.rows()), d = static_cast<int>(X.cols()), K = o.components;
  std::mt19937_64 rng(mix_seed(o.seed, static_cast<std::uint64_t>(start)));
  std::vector<int> centres;
  centres.push_back(std::min(n - 1, static_cast<int>(uniform01(rng) * n)));
  VecX d2 = (X.rowwise() - X.row(centres[0])).rowwise().squaredNorm();
  while (static_cast<int>(centres.size()) < K) {
    const double total = d2.sum();
    int pick = n - 1;
    if (total > 0) {
      // First point whose cumulative D^2 weight passes the draw; points
      // with zero weight (already centres) are never picked.
      const double target = uniform01(rng) * total;
      double acc = 0.0;
      for (int i = 0; i < n; ++i) {
        if (d2[i] <= 0) continue;
        acc += d2[i];
        pick = i;
        if (acc > target) break;
      }
    } else {
      pick = std::min(n - 1, static_cast<int>(uniform01(rng) * n));
    }
    centres.push_back(pick);
    d2 = d2.cwiseMin((X.rowwise() - X.row(pick)).rowwise().squaredNorm());
  }

  Run run;
  Model& m = run.model;
  m.weights = VecX::Constant(K, 1.0 / K);
  m.means.resize(K, d);
  for (int k = 0; k < K; ++k) m.means.row(k) = X.row(centres[k]);
  MatX data_cov = covariance_of(X);
  data_cov.diagonal().array() += o.regularization * std::max(data_cov.trace(), trace_floor) / d + variance_floor;
  m.covs.assign(K, data_cov);  // kept by components that get no point below
  MatX R = MatX::Zero(n, K);
  for (int i = 0; i < n; ++i) {
    int best = 0;
    double bd = (X.row(i) - m.means.row(0)).squaredNorm();
    for (int k = 1; k < K; ++k) {
      const double dk = (X.row(i) - m.means.row(k)).squaredNorm();
      if (dk < bd) bd = dk, best = k;
    }
    R(i, best) = 1.0;
  }
  maximize(X, R, o.regularization, trace_floor, variance_floor, m);

  for (int it = 0;; ++it) {
    if (!log_densities(m, X, R)) return run;
    const double L = normalize_responsibilities(R);
    if (!std::isfinite(L)) return run;
    run.history.push_back(L);
    run.iterations = it;
    if (it > 0 && std::abs(L - run.history[it - 1]) <= o.tolerance * std::abs(L)) {
      run.converged = true;
      break;
    }
    if (it == o.max_iterations) break;
    maximize(X, R, o.regularization, trace_floor, variance_floor, m);
  }
  run.ok = true;
  run.logL = run.history.back();
  run.resp = std::move(R);
  return run;
}

void require_points(const MatX& X, int components) {
  if (X.rows() < 1 || X.cols() < 1) throw InputError("gaussian mixture: no points");
  if (!X.allFinite()) throw InputError("gaussian mixture: a point has a non-finite coordinate");
  if (components < 1 || components > X.rows())
    throw InputError("gaussian mixture: " + std::to_string(components) + " components for " + std::to_string(X.rows()) +
                     " points (need 1 <= K <= N)");
}

}  // namespace

int gmm_parameter_count(int components, int dimensions) {
  return components * (dimensions + dimensions * (dimensions + 1) / 2) + components - 1;
}

double gmm_bic(double log_likelihood, int components, int dimensions, int points) {
  return -2.0 * log_likelihood + gmm_parameter_count(components, dimensions) * std::log(double(points));
}

GaussianMixture fit_gaussian_mixture(const MatX& points, const GmmOptions& options) {
  require_points(points, options.components);
  if (options.restarts < 1 || options.max_iterations < 1 || !(options.tolerance >= 0) ||
      !(options.regularization > 0) || !std::isfinite(options.regularization) || !(options.min_variance >= 0))
    throw InputError(
        "gaussian mixture: need restarts >= 1, max_iterations >= 1, tolerance >= 0, regularization > 0, "
        "min_variance >= 0");
  const double data_trace = covariance_of(points).trace();
  if (!(data_trace > 0)) throw InputError("gaussian mixture: all points coincide; there is nothing to cluster");
  const double trace_floor = 1e-6 * data_trace;
  const double variance_floor = options.min_variance * data_trace / double(points.cols());

  std::vector<Run> runs(options.restarts);
#pragma omp parallel for schedule(dynamic)
  for (int s = 0; s < options.restarts; ++s) runs[s] = run_em(points, options, s, trace_floor, variance_floor);
  int best = -1;
  for (int s = 0; s < options.restarts; ++s)
    if (runs[s].ok && (best < 0 || runs[s].logL > runs[best].logL)) best = s;
  if (best < 0)
    throw NumericalError("gaussian mixture: every start with " + std::to_string(options.components) +
                         " components met a covariance that is not positive definite");

  Run& r = runs[best];
  GaussianMixture g;
  const int n = static_cast<int>(points.rows()), K = options.components;
  g.weights = std::move(r.model.weights);
  g.means = std::move(r.model.means);
  g.covariances = std::move(r.model.covs);
  g.log_likelihood = r.logL;
  g.bic = gmm_bic(r.logL, K, static_cast<int>(points.cols()), n);
  g.iterations = r.iterations;
  g.converged = r.converged;
  g.restart = best;
  g.log_likelihood_history = std::move(r.history);
  g.responsibilities = std::move(r.resp);
  g.labels.resize(n);
  g.sizes.assign(K, 0);
  for (int i = 0; i < n; ++i) {
    Eigen::Index k = 0;
    g.responsibilities.row(i).maxCoeff(&k);
    g.labels[i] = static_cast<int>(k);
    ++g.sizes[k];
  }
  return g;
}

MatX gmm_responsibilities(const GaussianMixture& model, const MatX& points, double* log_likelihood) {
  const Eigen::Index K = model.weights.size();
  if (K < 1 || model.means.rows() != K || static_cast<Eigen::Index>(model.covariances.size()) != K)
    throw InputError("gaussian mixture: the model is empty or inconsistent");
  if (points.cols() != model.means.cols() || !points.allFinite())
    throw InputError("gaussian mixture: points have " + std::to_string(points.cols()) +
                     " coordinates (or a non-finite one), the model " + std::to_string(model.means.cols()));
  const Model m{model.weights, model.means, model.covariances};
  MatX R;
  if (!log_densities(m, points, R))
    throw NumericalError("gaussian mixture: a component covariance is not positive definite");
  const double L = normalize_responsibilities(R);
  if (log_likelihood) *log_likelihood = L;
  return R;
}

GmmSelection select_gaussian_mixture(const MatX& points, int kmin, int kmax, const GmmOptions& options) {
  if (kmin < 1 || kmax < kmin || kmax > points.rows())
    throw InputError("gaussian mixture: component range [" + std::to_string(kmin) + ", " + std::to_string(kmax) +
                     "] is not within [1, " + std::to_string(points.rows()) + "]");
  GmmSelection sel;
  for (int K = kmin; K <= kmax; ++K) {
    GmmOptions o = options;
    o.components = K;
    GaussianMixture g = fit_gaussian_mixture(points, o);
    sel.components.push_back(K);
    sel.bic.push_back(g.bic);
    if (K == kmin || g.bic < sel.best.bic) sel.best = std::move(g);
  }
  return sel;
}

}  // namespace msfab
