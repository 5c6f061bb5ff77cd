#pragma once
// Gaussian mixture clustering of embedded microstructures (thesis §3.3.1):
// each component of the mixture fitted in the Isomap space is a candidate
// structure family. Full covariances, fitted by expectation maximization
// from k-means++ starts; the number of components is chosen by BIC.
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace msfab {

struct GmmOptions {
  int components = 2;
  int restarts = 4;          // independent k-means++ starts; the best log-likelihood wins
  int max_iterations = 500;  // EM iterations (M-steps) per start
  double tolerance = 1e-8;   // stop when |L_t - L_{t-1}| <= tolerance * |L_t|
  // Each covariance gets regularization * max(trace(S), 1e-6 trace(data)) / d
  // added to its diagonal: relative to the component's own scale, with a
  // floor for a component that has collapsed onto a single point.
  double regularization = 1e-6;
  // min_variance * trace(data) / d is added to every covariance's diagonal:
  // the smallest cluster width the mixture resolves. Without it, clusters
  // collapse onto groups of (nearly) identical points, whose likelihood
  // grows without bound and wins any BIC comparison. 0: off.
  double min_variance = 0.0;
  std::uint64_t seed = 1;
};

struct GaussianMixture {
  VecX weights;                   // K, summing to 1
  MatX means;                     // K x d, one row per component
  std::vector<MatX> covariances;  // K matrices d x d
  double log_likelihood = 0.0;    // sum over points of ln p(x)
  double bic = 0.0;
  int iterations = 0;  // M-steps of the winning start
  bool converged = false;
  int restart = 0;  // which start won
  // ln-likelihood after every E-step of the winning start, the first from
  // the k-means++ initialization; the last equals log_likelihood.
  std::vector<double> log_likelihood_history;
  MatX responsibilities;    // N x K, rows summing to 1
  std::vector<int> labels;  // N: argmax responsibility (lowest index on ties)
  std::vector<int> sizes;   // K: number of points per label
};

// Free parameters of a K-component full-covariance mixture in d dimensions:
// K (d + d (d + 1) / 2) + K - 1.
int gmm_parameter_count(int components, int dimensions);
// -2 ln L + p ln N.
double gmm_bic(double log_likelihood, int components, int dimensions, int points);

// Fits to the rows of `points` (N x d). Starts run in parallel, each
// seeded from options.seed and its number alone, so the result does not
// depend on the thread count. InputError for bad options, non-finite
// points, fewer points than components, or points without spread;
// NumericalError if every start failed.
GaussianMixture fit_gaussian_mixture(const MatX& points, const GmmOptions& options);

// Responsibilities (N x K) of `points` under a fitted model, and the total
// log-likelihood through `log_likelihood` when not null.
MatX gmm_responsibilities(const GaussianMixture& model, const MatX& points, double* log_likelihood = nullptr);

struct GmmSelection {
  GaussianMixture best;         // the model with the smallest BIC (smaller K on ties)
  std::vector<int> components;  // kmin..kmax
  std::vector<double> bic;      // per entry of components
};
// Fits K = kmin..kmax components with `options` (its `components` is
// ignored) and keeps the minimum-BIC model. InputError unless
// 1 <= kmin <= kmax <= N.
GmmSelection select_gaussian_mixture(const MatX& points, int kmin, int kmax, const GmmOptions& options);

}  // namespace msfab
