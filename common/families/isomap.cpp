#include "families/isomap.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <string>

#include "core/errors.hpp"

namespace msfab {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Single-source shortest paths into row `out`.
void dijkstra(const NeighborGraph& g, int source, double* out) {
  const int n = static_cast<int>(g.size());
  std::fill(out, out + n, kInf);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  out[source] = 0.0;
  queue.emplace(0.0, source);
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > out[v]) continue;  // a stale entry: v was reached more cheaply since
    for (const GraphEdge& e : g[v]) {
      const double nd = d + e.length;
      if (nd < out[e.target]) {
        out[e.target] = nd;
        queue.emplace(nd, e.target);
      }
    }
  }
}

}  // namespace

void require_distance_matrix(const MatX& D) {
  if (D.rows() != D.cols() || D.rows() == 0)
    throw InputError("isomap: the distance matrix must be square and non-empty, got " + std::to_string(D.rows()) +
                     " x " + std::to_string(D.cols()));
  if (!D.allFinite() || D.minCoeff() < 0)
    throw InputError("isomap: the distance matrix has a negative or non-finite entry");
  if (D.diagonal().cwiseAbs().maxCoeff() != 0) throw InputError("isomap: the distance matrix has a non-zero diagonal");
  const double asym = (D - D.transpose()).cwiseAbs().maxCoeff();
  if (asym > 1e-9 * D.maxCoeff())
    throw InputError("isomap: the distance matrix is not symmetric (largest |D - D^T| = " + std::to_string(asym) + ")");
}

NeighborGraph knn_graph(const MatX& D, int k) {
  require_distance_matrix(D);
  const int n = static_cast<int>(D.rows());
  if (k < 1 || k >= n)
    throw InputError("isomap: neighbours k = " + std::to_string(k) + " must be in [1, " + std::to_string(n - 1) +
                     "] for " + std::to_string(n) + " points");
  std::vector<std::vector<char>> linked(n, std::vector<char>(n, 0));
  std::vector<int> order;
  for (int i = 0; i < n; ++i) {
    order.clear();
    for (int j = 0; j < n; ++j)
      if (j != i) order.push_back(j);
    // Ordering by (distance, index) makes ties, e.g. duplicate structures,
    // resolve the same way on every run.
    std::partial_sort(order.begin(), order.begin() + k, order.end(),
                      [&](int a, int b) { return D(i, a) != D(i, b) ? D(i, a) < D(i, b) : a < b; });
    for (int r = 0; r < k; ++r) linked[i][order[r]] = linked[order[r]][i] = 1;
  }
  NeighborGraph g(n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      if (linked[i][j]) g[i].push_back({j, 0.5 * (D(i, j) + D(j, i))});
  return g;
}

std::vector<int> connected_components(const NeighborGraph& graph) {
  const int n = static_cast<int>(graph.size());
  std::vector<int> comp(n, -1), stack;
  int count = 0;
  for (int s = 0; s < n; ++s) {
    if (comp[s] >= 0) continue;
    comp[s] = count;
    stack.assign(1, s);
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      for (const GraphEdge& e : graph[v])
        if (comp[e.target] < 0) comp[e.target] = count, stack.push_back(e.target);
    }
    ++count;
  }
  return comp;
}

MatX geodesic_distances(const NeighborGraph& graph) {
  const int n = static_cast<int>(graph.size());
  MatX G(n, n);
  for (const auto& edges : graph)
    for (const GraphEdge& e : edges)
      if (e.target < 0 || e.target >= n || !(e.length >= 0))
        throw InputError("isomap: graph edge to node " + std::to_string(e.target) + " with length " +
                         std::to_string(e.length) + " (nodes 0.." + std::to_string(n - 1) + ", lengths >= 0)");
        // Column s of the column-major G is contiguous: the rows of source s.
#pragma omp parallel for schedule(dynamic)
  for (int s = 0; s < n; ++s) dijkstra(graph, s, G.col(s).data());
  return 0.5 * (G + G.transpose());
}

MdsResult classical_mds(const MatX& D, int dimensions) {
  const int n = static_cast<int>(D.rows());
  if (D.rows() != D.cols() || n == 0 || !D.allFinite())
    throw InputError("mds: the distance matrix must be square, non-empty and finite");
  if (dimensions < 1 || dimensions > n)
    throw InputError("mds: dimensions = " + std::to_string(dimensions) + " must be in [1, " + std::to_string(n) + "]");
  // B = -1/2 J D^2 J with J = I - 11^T/n: the Gram matrix of centred points
  // whenever D is Euclidean.
  MatX B = D.cwiseAbs2();
  const VecX row_mean = B.rowwise().mean();
  const VecX col_mean = B.colwise().mean().transpose();
  const double mean = B.mean();
  B.colwise() -= row_mean;
  B.rowwise() -= col_mean.transpose();
  B.array() += mean;
  B *= -0.5;
  B = 0.5 * (B + B.transpose());
  const Eigen::SelfAdjointEigenSolver<MatX> eig(B);
  if (eig.info() != Eigen::Success) throw NumericalError("mds: the eigensolver failed on the centred Gram matrix");
  MdsResult r;
  r.eigenvalues.resize(dimensions);
  r.coordinates.resize(n, dimensions);
  for (int a = 0; a < dimensions; ++a) {
    const int col = n - 1 - a;  // eigenvalues come ascending
    const double lambda = eig.eigenvalues()[col];
    VecX v = eig.eigenvectors().col(col);
    Eigen::Index big = 0;
    for (Eigen::Index q = 1; q < v.size(); ++q)
      if (std::abs(v[q]) > std::abs(v[big])) big = q;
    if (v[big] < 0) v = -v;
    r.eigenvalues[a] = lambda;
    r.coordinates.col(a) = v * std::sqrt(std::max(lambda, 0.0));
  }
  return r;
}

double residual_variance(const MatX& D, const MatX& coordinates) {
  const Eigen::Index n = D.rows();
  if (D.cols() != n || coordinates.rows() != n)
    throw InputError("residual variance: " + std::to_string(n) + " x " + std::to_string(D.cols()) +
                     " distances do not match " + std::to_string(coordinates.rows()) + " embedded points");
  double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0, count = 0;
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::Index i = 0; i < j; ++i) {
      const double x = D(i, j), y = (coordinates.row(i) - coordinates.row(j)).norm();
      sx += x, sy += y, sxx += x * x, syy += y * y, sxy += x * y, count += 1;
    }
  if (count == 0) return 0.0;
  const double vx = sxx - sx * sx / count, vy = syy - sy * sy / count, cxy = sxy - sx * sy / count;
  if (!(vx > 0) || !(vy > 0)) return vx > 0 || vy > 0 ? 1.0 : 0.0;
  return std::max(0.0, 1.0 - cxy * cxy / (vx * vy));
}

int connect_components(NeighborGraph& graph, const MatX& D) {
  const std::vector<int> comp = connected_components(graph);
  const int n = static_cast<int>(graph.size());
  const int ncomp = n ? *std::max_element(comp.begin(), comp.end()) + 1 : 0;
  if (ncomp <= 1) return 0;
  // The shortest edge between every pair of components (ties: smallest
  // indices, from the scan order), then Kruskal over the components.
  struct Link {
    double length;
    int i, j;
  };
  std::vector<Link> best(std::size_t(ncomp) * ncomp, {std::numeric_limits<double>::infinity(), -1, -1});
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      const int a = std::min(comp[i], comp[j]), b = std::max(comp[i], comp[j]);
      if (a == b) continue;
      Link& l = best[std::size_t(a) * ncomp + b];
      if (D(i, j) < l.length) l = {D(i, j), i, j};
    }
  std::vector<Link> links;
  for (int a = 0; a < ncomp; ++a)
    for (int b = a + 1; b < ncomp; ++b) links.push_back(best[std::size_t(a) * ncomp + b]);
  std::stable_sort(links.begin(), links.end(), [](const Link& x, const Link& y) { return x.length < y.length; });
  std::vector<int> parent(ncomp);
  for (int c = 0; c < ncomp; ++c) parent[c] = c;
  const auto root = [&](int c) {
    while (parent[c] != c) c = parent[c] = parent[parent[c]];
    return c;
  };
  const auto insert = [&](int from, int to, double length) {
    std::vector<GraphEdge>& edges = graph[from];
    const auto at =
        std::lower_bound(edges.begin(), edges.end(), to, [](const GraphEdge& e, int t) { return e.target < t; });
    edges.insert(at, GraphEdge{to, length});
  };
  int added = 0;
  for (const Link& l : links) {
    const int a = root(comp[l.i]), b = root(comp[l.j]);
    if (a == b) continue;
    parent[a] = b;
    insert(l.i, l.j, l.length);
    insert(l.j, l.i, l.length);
    ++added;
  }
  return added;
}

IsomapResult isomap(const MatX& D, const IsomapOptions& options) {
  NeighborGraph graph = knn_graph(D, options.neighbors);
  const int n = static_cast<int>(graph.size());
  std::vector<int> comp = connected_components(graph);
  int ncomp = *std::max_element(comp.begin(), comp.end()) + 1;
  const int components_before = ncomp;
  if (options.connect && ncomp > 1 && !options.require_connected) {
    connect_components(graph, D);
    comp = connected_components(graph);
    ncomp = 1;
  }
  std::vector<int> sizes(ncomp, 0);
  for (int c : comp) ++sizes[c];
  if (options.require_connected && ncomp > 1) {
    std::string list;
    for (int c = 0; c < ncomp; ++c) list += (c ? ", " : "") + std::to_string(sizes[c]);
    throw InputError("isomap: the " + std::to_string(options.neighbors) + "-nearest-neighbour graph has " +
                     std::to_string(ncomp) + " components (sizes " + list +
                     "); raise the neighbour count or embed the largest component");
  }
  // max_element returns the first maximum: the component with the smaller index.
  const int largest = static_cast<int>(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
  IsomapResult r;
  r.components = components_before;
  for (int i = 0; i < n; ++i) (comp[i] == largest ? r.kept : r.left_out).push_back(i);
  const int m = static_cast<int>(r.kept.size());
  if (options.dimensions < 1 || options.dimensions + 1 > m)
    throw InputError("isomap: " + std::to_string(options.dimensions) + " dimensions need at least " +
                     std::to_string(options.dimensions + 1) + " connected points, the largest component has " +
                     std::to_string(m));
  NeighborGraph sub;
  if (ncomp == 1) {
    sub = graph;
  } else {
    std::vector<int> local(n, -1);
    for (int r2 = 0; r2 < m; ++r2) local[r.kept[r2]] = r2;
    sub.resize(m);
    for (int r2 = 0; r2 < m; ++r2)
      for (const GraphEdge& e : graph[r.kept[r2]]) sub[r2].push_back({local[e.target], e.length});
  }
  r.geodesic = geodesic_distances(sub);
  MdsResult mds = classical_mds(r.geodesic, options.dimensions);
  r.coordinates = std::move(mds.coordinates);
  r.eigenvalues = std::move(mds.eigenvalues);
  r.residual_variance = residual_variance(r.geodesic, r.coordinates);
  return r;
}

}  // namespace msfab
