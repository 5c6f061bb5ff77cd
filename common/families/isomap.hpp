#pragma once
// Isomap (Tenenbaum et al. 2000) over a precomputed distance matrix: the
// nonlinear dimensionality reduction that groups microstructures into
// families (thesis §3.3.1). Distances are trusted only between near
// neighbours; long distances are replaced by shortest paths through the
// neighbour graph, so a chain of gradually morphing structures unrolls
// into a line even when its ends look nothing alike.
#include <vector>

#include "core/types.hpp"

namespace msfab {

struct GraphEdge {
  int target = 0;
  double length = 0.0;
};
// adjacency[i]: the edges of node i, sorted by target.
using NeighborGraph = std::vector<std::vector<GraphEdge>>;

// Throws InputError unless D is square, finite, non-negative, has a zero
// diagonal and is symmetric to within 1e-9 of its largest entry.
void require_distance_matrix(const MatX& D);

// Edge i-j when j is among the k nearest of i or i among the k nearest of
// j (equal distances ordered by index), with length D(i, j). InputError
// unless 1 <= k < number of points.
NeighborGraph knn_graph(const MatX& D, int k);

// Component number per node, numbered in order of each component's
// smallest node.
std::vector<int> connected_components(const NeighborGraph& graph);

// Shortest path lengths between all pairs (Dijkstra from every node, in
// parallel); infinity between components. Symmetrized as the mean of the
// two directions, which differ only by summation order.
MatX geodesic_distances(const NeighborGraph& graph);

struct MdsResult {
  MatX coordinates;  // points x dimensions
  VecX eigenvalues;  // the top `dimensions` of -J D^2 J / 2, descending
};
// Classical multidimensional scaling: coordinate axis a is eigenvector a
// times sqrt(max(eigenvalue a, 0)), its sign chosen so the component of
// largest magnitude (first such index on ties) is positive. InputError
// unless 1 <= dimensions <= number of points.
MdsResult classical_mds(const MatX& D, int dimensions);

// 1 - R^2, R the linear correlation between the entries i < j of D and the
// Euclidean distances between rows of `coordinates`. 0 for a perfect
// embedding; with fewer than two distinct distances on either side R is
// undefined: 0 if neither side varies, else 1.
double residual_variance(const MatX& D, const MatX& coordinates);

// Joins the components of a neighbour graph by the shortest edges of D
// between them (Kruskal's rule on the components: the overall shortest
// edge between two not yet joined components first), so a graph of k
// components gains k - 1 edges. Separate families of structures stay far
// apart in the embedding, joined only through their closest members.
// Returns the number of edges added.
int connect_components(NeighborGraph& graph, const MatX& D);

struct IsomapOptions {
  int neighbors = 8;
  int dimensions = 3;
  // true: a neighbour graph with several components is an InputError;
  // false: only the largest component is embedded (unless joined below).
  bool require_connected = false;
  // true: components are joined (connect_components) before embedding, so
  // every point is embedded.
  bool connect = false;
};

struct IsomapResult {
  MatX coordinates;              // kept.size() x dimensions; row r is point kept[r]
  std::vector<int> kept;         // input indices embedded, ascending
  std::vector<int> left_out;     // input indices outside the largest component
  int components = 1;            // of the neighbour graph (before joining)
  VecX eigenvalues;              // descending
  double residual_variance = 0;  // of the embedding against the geodesic distances
  MatX geodesic;                 // kept x kept
};
// The largest component (ties: the one with the smallest index) is
// embedded. InputError for a bad matrix or options, for a component with
// fewer points than dimensions + 1, and, with require_connected, for a
// disconnected graph (the message gives the component sizes).
IsomapResult isomap(const MatX& D, const IsomapOptions& options);

}  // namespace msfab
