#pragma once
// Candidate structures per design cell (thesis §3.5, step 1): the k nearest
// microstructures to the cell's target in the normalized material space,
// optionally together with every structure within a radius.
//
// Distances are Euclidean in the unit cube both artifacts share. Ties are
// broken by the lower structure index, so the result is one well-defined
// list whatever the thread count or the tree's shape: a kd-tree query and
// the brute-force reference return the same indices in the same order.
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace msfab {

struct Neighbour {
  std::int32_t index = 0;  // row of the point set
  double distance2 = 0;    // squared Euclidean distance
};

// A kd-tree over a fixed set of points (rows of `points`), split at the
// median of the widest coordinate, leaves of up to 8 points.
class KdTree {
 public:
  explicit KdTree(const MatX& points);

  int size() const { return n_; }
  int dimension() const { return d_; }
  // The min(k, size) nearest points to q, sorted by (distance, index).
  std::vector<Neighbour> nearest(const double* q, int k) const;
  // Every point with distance <= radius, sorted by (distance, index).
  std::vector<Neighbour> within(const double* q, double radius) const;

 private:
  struct Node {
    int begin = 0, end = 0;  // range of order_
    int axis = -1;           // -1: leaf
    double split = 0;
    int left = -1, right = -1;
  };
  int build(int begin, int end);
  double distance2(const double* q, int point) const;
  void search_nearest(int node, const double* q, int k, std::vector<Neighbour>& heap) const;
  void search_within(int node, const double* q, double r2, std::vector<Neighbour>& out) const;

  int n_ = 0, d_ = 0;
  std::vector<double> xyz_;  // points, row-major
  std::vector<int> order_;   // point indices, grouped by leaf
  std::vector<Node> nodes_;
};

// The same queries by scanning every point (the tests' reference).
std::vector<Neighbour> brute_force_nearest(const MatX& points, const double* q, int k);
std::vector<Neighbour> brute_force_within(const MatX& points, const double* q, double radius);

struct CandidateOptions {
  int k = 16;         // nearest structures per cell (>= 1)
  double radius = 0;  // > 0: also every structure within this distance
  // Distances over the moduli and Poisson ratios only, the density (the
  // space's last coordinate) left out: a cell then gets the structures
  // whose stiffness matches, whatever their mass (design_candidates).
  bool stiffness_only = false;
  // > 0: of a cell's candidates keep those whose property gap (relative,
  // Frobenius norm of C) is at most max(max_gap, the cell's smallest gap),
  // so the boundary descent cannot trade the stiffness away for a better
  // fit of the faces (design_candidates).
  double max_gap = 0;
};

// Candidates of every cell in compressed rows: cell c's are entries
// offsets[c] .. offsets[c + 1] - 1, nearest first. Cells with
// wanted[c] == false get none.
struct CellCandidates {
  std::vector<std::int64_t> offsets;  // cells + 1
  std::vector<std::int32_t> structure;
  std::vector<double> distance;  // Euclidean, normalized units

  std::int64_t cells() const { return std::int64_t(offsets.size()) - 1; }
  std::int64_t count(std::int64_t c) const { return offsets[c + 1] - offsets[c]; }
  // Distance to the nearest candidate (0 for a cell with none).
  double nearest_distance(std::int64_t c) const { return count(c) > 0 ? distance[offsets[c]] : 0.0; }
};

// targets: cells x d; points: structures x d. Parallel over cells (OpenMP),
// deterministic.
CellCandidates find_candidates(const MatX& targets, const std::vector<bool>& wanted, const MatX& points,
                               const CandidateOptions& options);

}  // namespace msfab
