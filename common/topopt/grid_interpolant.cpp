#include "topopt/grid_interpolant.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace msfab {
namespace {

// One axis's contribution: the nodes that carry weight at a coordinate, the
// weights and their derivatives with respect to t.
struct HermiteAxisWeights {
  int node[4] = {0, 0, 0, 0};
  double weight[4] = {0, 0, 0, 0}, rate[4] = {0, 0, 0, 0};
  int count = 0;
  void add(int j, double w, double dw) {
    for (int k = 0; k < count; ++k)
      if (node[k] == j) {
        weight[k] += w, rate[k] += dw;
        return;
      }
    node[count] = j, weight[count] = w, rate[count] = dw, ++count;
  }
};

// The Catmull-Rom tangent at node j of an axis of n nodes, in index units,
// as a combination of node values: added to `out` with factor f (and df).
void add_hermite_tangent(HermiteAxisWeights& out, int j, int n, double f, double df) {
  if (j == 0) {
    out.add(1, f, df), out.add(0, -f, -df);
  } else if (j == n - 1) {
    out.add(n - 1, f, df), out.add(n - 2, -f, -df);
  } else {
    out.add(j + 1, 0.5 * f, 0.5 * df), out.add(j - 1, -0.5 * f, -0.5 * df);
  }
}

HermiteAxisWeights hermite_axis_weights(double t, int n) {
  HermiteAxisWeights w;
  if (n == 1) {
    w.add(0, 1.0, 0.0);
    return w;
  }
  const bool clamped = t < 0 || t > 1;
  const double x = std::clamp(t, 0.0, 1.0) * (n - 1);
  const int i = std::min(int(std::floor(x)), n - 2);
  const double s = x - i, s2 = s * s, s3 = s2 * s;
  // d/dt = (n - 1) d/ds; no slope outside the box.
  const double scale = clamped ? 0.0 : double(n - 1);
  w.add(i, 2 * s3 - 3 * s2 + 1, scale * (6 * s2 - 6 * s));
  w.add(i + 1, -2 * s3 + 3 * s2, scale * (-6 * s2 + 6 * s));
  add_hermite_tangent(w, i, n, s3 - 2 * s2 + s, scale * (3 * s2 - 4 * s + 1));
  add_hermite_tangent(w, i + 1, n, s3 - s2, scale * (3 * s2 - 2 * s));
  return w;
}

}  // namespace

GridInterpolant::GridInterpolant(std::vector<int> sizes, MatX values)
    : sizes_(std::move(sizes)), values_(std::move(values)) {
  if (sizes_.empty()) throw std::invalid_argument("GridInterpolant: no axes");
  Eigen::Index points = 1;
  for (int n : sizes_) {
    if (n < 1) throw std::invalid_argument("GridInterpolant: an axis without nodes");
    points *= n;
  }
  if (values_.rows() != points) throw std::invalid_argument("GridInterpolant: one value row per grid node");
}

void GridInterpolant::evaluate(const VecX& t, VecX& value, MatX* gradient) const {
  const int d = axes();
  if (t.size() != d) throw std::invalid_argument("GridInterpolant::evaluate: one coordinate per axis");
  std::vector<HermiteAxisWeights> w(static_cast<std::size_t>(d));
  for (int a = 0; a < d; ++a) w[std::size_t(a)] = hermite_axis_weights(t[a], sizes_[std::size_t(a)]);
  value = VecX::Zero(channels());
  if (gradient) *gradient = MatX::Zero(channels(), d);
  // Every combination of the axes' weighted nodes (at most 4^d).
  std::vector<int> pick(static_cast<std::size_t>(d), 0);
  for (;;) {
    Eigen::Index node = 0;
    double weight = 1;
    for (int a = 0; a < d; ++a) {
      const HermiteAxisWeights& wa = w[std::size_t(a)];
      node = node * sizes_[std::size_t(a)] + wa.node[pick[std::size_t(a)]];
      weight *= wa.weight[pick[std::size_t(a)]];
    }
    value += weight * values_.row(node).transpose();
    if (gradient)
      for (int k = 0; k < d; ++k) {
        double dk = 1;
        for (int a = 0; a < d; ++a) {
          const HermiteAxisWeights& wa = w[std::size_t(a)];
          dk *= a == k ? wa.rate[pick[std::size_t(a)]] : wa.weight[pick[std::size_t(a)]];
        }
        gradient->col(k) += dk * values_.row(node).transpose();
      }
    int a = d - 1;
    while (a >= 0 && ++pick[std::size_t(a)] == w[std::size_t(a)].count) pick[std::size_t(a)] = 0, --a;
    if (a < 0) break;
  }
}

}  // namespace msfab
