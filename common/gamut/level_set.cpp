#include "gamut/level_set.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <queue>
#include <sstream>
#include <unordered_map>

#include "core/errors.hpp"

namespace msfab {
namespace {

constexpr double kUnknown = std::numeric_limits<double>::infinity();

// Decodes a flat node index into per-axis indices (axis 0 fastest).
void decode(long long flat, int cells, std::vector<int>& index) {
  for (std::size_t a = 0; a < index.size(); ++a) index[a] = static_cast<int>(flat % cells), flat /= cells;
}

// A grid of cells^d nodes at lo + (i + 1/2) h per axis, axis 0 fastest.
struct NodeGrid {
  int d, cells;
  double lo, h;
  double extent;  // (1 + 2 margin): the grid's edge length
  std::vector<long long> stride;
  long long nodes;
};

// 1. The Zhu-Bridson implicit function at every node, |x - xbar(x)| - r,
// from buckets of edge 2r; kUnknown where no sample lies within 2r.
std::vector<double> implicit_function(const std::vector<VecX>& points, const NodeGrid& g, double r) {
  const int d = g.d;
  const double h = g.h, reach = 2 * r;
  const long long buckets_per_axis = static_cast<long long>(std::ceil(g.extent / reach)) + 2;
  auto bucket_key = [&](const std::vector<long long>& b) {
    long long key = 0;
    for (int a = d - 1; a >= 0; --a) key = key * buckets_per_axis + b[a];
    return key;
  };
  std::unordered_map<long long, std::vector<int>> buckets;
  std::vector<long long> b(d);
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (int a = 0; a < d; ++a) b[a] = static_cast<long long>(std::floor((points[i][a] - g.lo) / reach)) + 1;
    buckets[bucket_key(b)].push_back(static_cast<int>(i));
  }
  long long neighbourhood = 1;
  for (int a = 0; a < d; ++a) neighbourhood *= 3;
  std::vector<double> phi0(g.nodes);
#pragma omp parallel for schedule(dynamic, 256)
  for (long long v = 0; v < g.nodes; ++v) {
    std::vector<int> index(d);
    std::vector<long long> home(d), nb(d);
    decode(v, g.cells, index);
    VecX x(d);
    for (int a = 0; a < d; ++a) {
      x[a] = g.lo + (index[a] + 0.5) * h;
      home[a] = static_cast<long long>(std::floor((x[a] - g.lo) / reach)) + 1;
    }
    VecX mean = VecX::Zero(d);
    double weight = 0;
    for (long long c = 0; c < neighbourhood; ++c) {
      long long rest = c;
      for (int a = 0; a < d; ++a) nb[a] = home[a] + rest % 3 - 1, rest /= 3;
      const auto it = buckets.find(bucket_key(nb));
      if (it == buckets.end()) continue;
      for (int i : it->second) {
        const double s2 = (points[i] - x).squaredNorm() / (reach * reach);
        if (s2 >= 1) continue;
        const double w = (1 - s2) * (1 - s2) * (1 - s2);
        mean += w * points[i];
        weight += w;
      }
    }
    phi0[v] = weight > 0 ? (x - mean / weight).norm() - r : kUnknown;
  }
  return phi0;
}

using DistanceHeap =
    std::priority_queue<std::pair<double, long long>, std::vector<std::pair<double, long long>>, std::greater<>>;

// 2. Nodes next to a sign change of phi0, with their distance estimated
// along the crossing axis (unknown nodes are outside): into u and the heap.
DistanceHeap seed_crossing_nodes(const std::vector<double>& phi0, const NodeGrid& g, std::vector<double>& u) {
  const int d = g.d;
  DistanceHeap heap;
  std::vector<int> index(d);
  for (long long v = 0; v < g.nodes; ++v) {
    decode(v, g.cells, index);
    const bool inside = phi0[v] < 0;
    double best = kUnknown;
    for (int a = 0; a < d; ++a)
      for (int step : {-1, 1}) {
        const int j = index[a] + step;
        if (j < 0 || j >= g.cells) continue;
        const long long w = v + step * g.stride[a];
        if ((phi0[w] < 0) == inside) continue;
        double dist;
        if (std::isfinite(phi0[v]) && std::isfinite(phi0[w]))
          dist = g.h * phi0[v] / (phi0[v] - phi0[w]);
        else
          dist = std::isfinite(phi0[v]) ? std::min(std::abs(phi0[v]), g.h) : g.h;
        best = std::min(best, std::abs(dist));
      }
    if (best < kUnknown) {
      u[v] = best;
      heap.push({best, v});
    }
  }
  return heap;
}

// 3. Fast marching of the unsigned distance u from the seeded nodes
// (first-order upwind Eikonal).
void fast_march(const NodeGrid& g, DistanceHeap& heap, std::vector<double>& u) {
  const int d = g.d;
  std::vector<char> accepted(static_cast<std::size_t>(g.nodes), 0);
  std::vector<int> index(d);
  std::vector<double> m;
  while (!heap.empty()) {
    const auto [value, v] = heap.top();
    heap.pop();
    if (accepted[v] || value > u[v]) continue;
    accepted[v] = 1;
    decode(v, g.cells, index);
    for (int a = 0; a < d; ++a)
      for (int step : {-1, 1}) {
        const int j = index[a] + step;
        if (j < 0 || j >= g.cells) continue;
        const long long w = v + step * g.stride[a];
        if (accepted[w]) continue;
        // Update w from its accepted neighbours, axis by axis.
        std::vector<int> wi(d);
        decode(w, g.cells, wi);
        m.clear();
        for (int b2 = 0; b2 < d; ++b2) {
          double best = kUnknown;
          for (int s2 : {-1, 1}) {
            const int k = wi[b2] + s2;
            if (k < 0 || k >= g.cells) continue;
            const long long q = w + s2 * g.stride[b2];
            if (accepted[q]) best = std::min(best, u[q]);
          }
          if (best < kUnknown) m.push_back(best);
        }
        std::sort(m.begin(), m.end());
        double sum = 0, sum2 = 0, solution = kUnknown;
        for (std::size_t k = 0; k < m.size(); ++k) {
          sum += m[k];
          sum2 += m[k] * m[k];
          const double kk = double(k + 1), disc = sum * sum - kk * (sum2 - g.h * g.h);
          if (disc < 0) break;
          const double candidate = (sum + std::sqrt(disc)) / kk;
          if (k + 1 < m.size() && candidate > m[k + 1]) {
            solution = candidate;
            continue;
          }
          solution = candidate;
          break;
        }
        if (solution < u[w]) {
          u[w] = solution;
          heap.push({solution, w});
        }
      }
  }
}

// 4. One explicit step of dPhi/dt = Laplacian(Phi), mirrored at the grid
// boundary, dt = h^2 / (4 d).
void smooth_once(const NodeGrid& g, std::vector<double>& phi) {
  const int d = g.d;
  const double dt = g.h * g.h / (4 * d);
  std::vector<double> next(g.nodes);
#pragma omp parallel for schedule(static)
  for (long long v = 0; v < g.nodes; ++v) {
    std::vector<int> index(d);
    decode(v, g.cells, index);
    double lap = 0;
    for (int a = 0; a < d; ++a) {
      const double lo = index[a] > 0 ? phi[v - g.stride[a]] : phi[v];
      const double hi = index[a] + 1 < g.cells ? phi[v + g.stride[a]] : phi[v];
      lap += (lo - 2 * phi[v] + hi) / (g.h * g.h);
    }
    next[v] = phi[v] + dt * lap;
  }
  phi.swap(next);
}

}  // namespace

double GamutLevelSet::node(const std::vector<int>& index) const {
  long long flat = 0;
  for (int a = 0; a < dim_; ++a) flat += index[a] * stride_[a];
  return phi_[flat];
}

GamutLevelSet GamutLevelSet::from_values(int d, int cells, double lower, double spacing, std::vector<double> values,
                                         double padding) {
  if (d < 1 || d > 6 || cells < 2 || !(spacing > 0) || !std::isfinite(lower))
    throw InputError("gamut level set: need dimension 1..6, cells >= 2, spacing > 0");
  if (!(padding >= 0) || !std::isfinite(padding)) throw InputError("gamut level set: padding must be finite and >= 0");
  GamutLevelSet ls;
  ls.dim_ = d;
  ls.cells_ = cells;
  ls.lo_ = lower;
  ls.h_ = spacing;
  ls.stride_.assign(d, 1);
  for (int a = 1; a < d; ++a) ls.stride_[a] = ls.stride_[a - 1] * cells;
  if (static_cast<long long>(values.size()) != ls.stride_[d - 1] * cells)
    throw InputError("gamut level set: " + std::to_string(values.size()) + " node values for " + std::to_string(cells) +
                     "^" + std::to_string(d) + " nodes");
  for (double v : values)
    if (!std::isfinite(v)) throw InputError("gamut level set: a node value is not finite");
  ls.phi_ = std::move(values);
  ls.padding_ = padding;
  return ls;
}

GamutLevelSet GamutLevelSet::shifted(double offset) const {
  GamutLevelSet out = *this;
  for (double& v : out.phi_) v += offset;
  out.padding_ = std::max(0.0, padding_ - offset);
  return out;
}

GamutLevelSet GamutLevelSet::from_points(const std::vector<VecX>& points, const LevelSetOptions& o) {
  if (points.empty()) throw InputError("gamut level set: no sample points");
  const int d = static_cast<int>(points[0].size());
  if (d < 1 || d > 6) throw InputError("gamut level set: dimension must be 1..6, got " + std::to_string(d));
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (points[i].size() != d)
      throw InputError("gamut level set: point " + std::to_string(i) + " has " + std::to_string(points[i].size()) +
                       " coordinates, the first has " + std::to_string(d));
    for (int a = 0; a < d; ++a)
      if (!(points[i][a] >= 0 && points[i][a] <= 1)) {
        std::ostringstream os;
        os << "gamut level set: point " << i << " coordinate " << a << " = " << points[i][a]
           << " is outside the normalized range [0, 1]";
        throw InputError(os.str());
      }
  }
  if (o.cells < 2) throw InputError("gamut level set: cells must be >= 2");
  if (!(o.margin >= 0) || !(o.radius >= 0) || o.smoothing_steps < 0)
    throw InputError("gamut level set: margin, radius and smoothing_steps must be >= 0");
  if (std::pow(double(o.cells), d) > double(1 << 26))
    throw InputError("gamut level set: " + std::to_string(o.cells) + "^" + std::to_string(d) +
                     " grid nodes is more than 2^26");

  GamutLevelSet ls;
  ls.dim_ = d;
  ls.cells_ = o.cells;
  ls.lo_ = -o.margin;
  ls.h_ = (1 + 2 * o.margin) / o.cells;
  ls.stride_.assign(d, 1);
  for (int a = 1; a < d; ++a) ls.stride_[a] = ls.stride_[a - 1] * o.cells;
  const long long n = ls.stride_[d - 1] * o.cells;
  const double h = ls.h_, r = o.radius > 0 ? o.radius : 1.5 * h;
  ls.padding_ = r;

  const NodeGrid grid{d, o.cells, ls.lo_, h, 1 + 2 * o.margin, ls.stride_, n};
  // 1-3. The implicit function, the nodes next to its zero crossing, and
  // fast marching from them to a signed distance everywhere.
  const std::vector<double> phi0 = implicit_function(points, grid, r);
  std::vector<double> u(n, kUnknown);
  DistanceHeap heap = seed_crossing_nodes(phi0, grid, u);
  if (heap.empty()) throw InputError("gamut level set: the samples leave no boundary on the grid (all inside or none)");
  fast_march(grid, heap, u);
  ls.phi_.resize(n);
  for (long long v = 0; v < n; ++v) ls.phi_[v] = phi0[v] < 0 ? -u[v] : u[v];

  // 4. Smoothing.
  for (int step = 0; step < o.smoothing_steps; ++step) smooth_once(grid, ls.phi_);
  return ls;
}

namespace {
// Interpolation cell and fractions of p; `outside` gets p minus its clamp.
void locate(const VecX& p, int dim, int cells, double lo, double h, std::vector<int>& base, VecX& frac, VecX& outside) {
  for (int a = 0; a < dim; ++a) {
    const double first = lo + 0.5 * h, last = lo + (cells - 0.5) * h;
    const double c = std::clamp(p[a], first, last);
    outside[a] = p[a] - c;
    const double t = (c - first) / h;
    base[a] = std::min(static_cast<int>(std::floor(t)), cells - 2);
    frac[a] = t - base[a];
  }
}
}  // namespace

double GamutLevelSet::value(const VecX& p) const {
  if (p.size() != dim_) throw std::invalid_argument("GamutLevelSet::value: wrong dimension");
  std::vector<int> base(dim_), corner(dim_);
  VecX frac(dim_), outside(dim_);
  locate(p, dim_, cells_, lo_, h_, base, frac, outside);
  double v = 0;
  for (int c = 0; c < (1 << dim_); ++c) {
    double w = 1;
    for (int a = 0; a < dim_; ++a) {
      const int bit = c >> a & 1;
      corner[a] = base[a] + bit;
      w *= bit ? frac[a] : 1 - frac[a];
    }
    v += w * node(corner);
  }
  return v + outside.norm();
}

VecX GamutLevelSet::gradient(const VecX& p) const {
  if (p.size() != dim_) throw std::invalid_argument("GamutLevelSet::gradient: wrong dimension");
  std::vector<int> base(dim_), corner(dim_);
  VecX frac(dim_), outside(dim_);
  locate(p, dim_, cells_, lo_, h_, base, frac, outside);
  VecX g = VecX::Zero(dim_);
  for (int c = 0; c < (1 << dim_); ++c) {
    for (int a = 0; a < dim_; ++a) corner[a] = base[a] + (c >> a & 1);
    const double value = node(corner);
    for (int a = 0; a < dim_; ++a) {
      if (outside[a] != 0) continue;  // clamped axis: the interpolant is constant along it
      double w = 1;
      for (int b2 = 0; b2 < dim_; ++b2) {
        const int bit = c >> b2 & 1;
        w *= b2 == a ? (bit ? 1.0 : -1.0) / h_ : (bit ? frac[b2] : 1 - frac[b2]);
      }
      g[a] += w * value;
    }
  }
  const double out = outside.norm();
  if (out > 0) g += outside / out;
  return g;
}

double GamutLevelSet::smooth_value(const VecX& p, VecX* gradient) const {
  if (p.size() != dim_) throw std::invalid_argument("GamutLevelSet::smooth_value: wrong dimension");
  // Per axis: the nearest node i, the offset u in [-1/2, 1/2], and the
  // quadratic B-spline weights of nodes i - 1, i, i + 1 and their slopes.
  std::vector<std::array<int, 3>> index(dim_);
  std::vector<std::array<double, 3>> w(dim_), dw(dim_);
  VecX outside = VecX::Zero(dim_);
  for (int a = 0; a < dim_; ++a) {
    double t = (p[a] - lo_) / h_ - 0.5;
    if (t < 0) outside[a] = t * h_, t = 0;
    if (t > cells_ - 1) outside[a] = (t - (cells_ - 1)) * h_, t = cells_ - 1;
    const int i = int(std::lround(t));
    const double u = t - i;
    w[a] = {0.5 * (0.5 - u) * (0.5 - u), 0.75 - u * u, 0.5 * (0.5 + u) * (0.5 + u)};
    const double slope = outside[a] != 0 ? 0.0 : 1.0 / h_;
    dw[a] = {-(0.5 - u) * slope, -2 * u * slope, (0.5 + u) * slope};
    for (int k = 0; k < 3; ++k) index[a][k] = std::clamp(i + k - 1, 0, cells_ - 1);
  }
  double v = 0;
  VecX g = VecX::Zero(dim_);
  std::vector<int> corner(dim_), digit(dim_, 0);
  int terms = 1;
  for (int a = 0; a < dim_; ++a) terms *= 3;
  for (int t = 0; t < terms; ++t) {
    int rest = t;
    for (int a = 0; a < dim_; ++a) digit[a] = rest % 3, rest /= 3, corner[a] = index[a][digit[a]];
    const double phi = node(corner);
    double weight = 1;
    for (int a = 0; a < dim_; ++a) weight *= w[a][digit[a]];
    v += weight * phi;
    if (!gradient) continue;
    for (int a = 0; a < dim_; ++a) {
      double wa = dw[a][digit[a]];
      for (int b = 0; b < dim_; ++b)
        if (b != a) wa *= w[b][digit[b]];
      g[a] += wa * phi;
    }
  }
  const double out = outside.norm();
  if (gradient) *gradient = out > 0 ? VecX(g + outside / out) : g;
  return v + out;
}

}  // namespace msfab
