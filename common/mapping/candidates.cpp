#include "mapping/candidates.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "cli/progress.hpp"

namespace msfab {
namespace {

constexpr int kLeafSize = 8;

bool closer(const Neighbour& a, const Neighbour& b) {
  return a.distance2 < b.distance2 || (a.distance2 == b.distance2 && a.index < b.index);
}

// Keeps the k best of what it is offered in a max-heap on (distance, index).
void offer(std::vector<Neighbour>& heap, int k, const Neighbour& candidate) {
  if (int(heap.size()) < k) {
    heap.push_back(candidate);
    std::push_heap(heap.begin(), heap.end(), closer);
  } else if (closer(candidate, heap.front())) {
    std::pop_heap(heap.begin(), heap.end(), closer);
    heap.back() = candidate;
    std::push_heap(heap.begin(), heap.end(), closer);
  }
}

// Squared distance summed in coordinate order, the same in every query, so
// equal points give bit-identical distances.
double squared_distance(const double* a, const double* b, int d) {
  double s = 0;
  for (int j = 0; j < d; ++j) {
    const double t = a[j] - b[j];
    s += t * t;
  }
  return s;
}

}  // namespace

KdTree::KdTree(const MatX& points) : n_(int(points.rows())), d_(int(points.cols())) {
  xyz_.resize(std::size_t(n_) * d_);
  for (int i = 0; i < n_; ++i)
    for (int j = 0; j < d_; ++j) xyz_[std::size_t(i) * d_ + j] = points(i, j);
  order_.resize(n_);
  std::iota(order_.begin(), order_.end(), 0);
  if (n_ > 0) build(0, n_);
}

int KdTree::build(int begin, int end) {
  const int id = int(nodes_.size());
  nodes_.push_back({begin, end, -1, 0, -1, -1});
  if (end - begin <= kLeafSize || d_ == 0) return id;
  int axis = 0;
  double widest = -1;
  for (int j = 0; j < d_; ++j) {
    double lo = xyz_[std::size_t(order_[begin]) * d_ + j], hi = lo;
    for (int p = begin; p < end; ++p) {
      const double v = xyz_[std::size_t(order_[p]) * d_ + j];
      lo = std::min(lo, v), hi = std::max(hi, v);
    }
    if (hi - lo > widest) widest = hi - lo, axis = j;
  }
  const int mid = (begin + end) / 2;
  auto key_less = [&](int a, int b) {
    const double va = xyz_[std::size_t(a) * d_ + axis], vb = xyz_[std::size_t(b) * d_ + axis];
    return va < vb || (va == vb && a < b);
  };
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end, key_less);
  const double split = xyz_[std::size_t(order_[mid]) * d_ + axis];
  const int left = build(begin, mid);
  const int right = build(mid, end);
  Node& node = nodes_[id];
  node.axis = axis, node.split = split, node.left = left, node.right = right;
  return id;
}

double KdTree::distance2(const double* q, int point) const {
  return squared_distance(q, &xyz_[std::size_t(point) * d_], d_);
}

// Left holds coordinates <= split and right >= split along the node's axis,
// so a whole side is at least (q - split)^2 away. A side is skipped only when
// that bound exceeds the current k-th distance strictly: a point at exactly
// that distance may still win on its lower index.
void KdTree::search_nearest(int id, const double* q, int k, std::vector<Neighbour>& heap) const {
  const Node& node = nodes_[id];
  if (node.axis < 0) {
    for (int p = node.begin; p < node.end; ++p) offer(heap, k, {order_[p], distance2(q, order_[p])});
    return;
  }
  const double diff = q[node.axis] - node.split;
  const int near = diff < 0 ? node.left : node.right, far = diff < 0 ? node.right : node.left;
  search_nearest(near, q, k, heap);
  if (int(heap.size()) < k || diff * diff <= heap.front().distance2) search_nearest(far, q, k, heap);
}

void KdTree::search_within(int id, const double* q, double r2, std::vector<Neighbour>& out) const {
  const Node& node = nodes_[id];
  if (node.axis < 0) {
    for (int p = node.begin; p < node.end; ++p) {
      const double d2 = distance2(q, order_[p]);
      if (d2 <= r2) out.push_back({order_[p], d2});
    }
    return;
  }
  const double diff = q[node.axis] - node.split;
  const int near = diff < 0 ? node.left : node.right, far = diff < 0 ? node.right : node.left;
  search_within(near, q, r2, out);
  if (diff * diff <= r2) search_within(far, q, r2, out);
}

std::vector<Neighbour> KdTree::nearest(const double* q, int k) const {
  std::vector<Neighbour> heap;
  k = std::min(k, n_);
  if (k <= 0) return heap;
  heap.reserve(std::size_t(k));
  search_nearest(0, q, k, heap);
  std::sort_heap(heap.begin(), heap.end(), closer);
  return heap;
}

std::vector<Neighbour> KdTree::within(const double* q, double radius) const {
  std::vector<Neighbour> out;
  if (n_ == 0 || !(radius >= 0)) return out;
  search_within(0, q, radius * radius, out);
  std::sort(out.begin(), out.end(), closer);
  return out;
}

std::vector<Neighbour> brute_force_nearest(const MatX& points, const double* q, int k) {
  std::vector<Neighbour> all = brute_force_within(points, q, INFINITY);
  all.resize(std::min(all.size(), std::size_t(std::max(k, 0))));
  return all;
}

std::vector<Neighbour> brute_force_within(const MatX& points, const double* q, double radius) {
  std::vector<Neighbour> out;
  const int d = int(points.cols());
  std::vector<double> row(static_cast<std::size_t>(d));
  for (int i = 0; i < int(points.rows()); ++i) {
    for (int j = 0; j < d; ++j) row[j] = points(i, j);
    const double d2 = squared_distance(q, row.data(), d);
    if (d2 <= radius * radius) out.push_back({i, d2});
  }
  std::sort(out.begin(), out.end(), closer);
  return out;
}

CellCandidates find_candidates(const MatX& targets, const std::vector<bool>& wanted, const MatX& points,
                               const CandidateOptions& options) {
  if (options.k < 1) throw std::invalid_argument("find_candidates: k must be >= 1");
  if (targets.cols() != points.cols()) throw std::invalid_argument("find_candidates: dimensions differ");
  if (std::int64_t(wanted.size()) != targets.rows()) throw std::invalid_argument("find_candidates: wanted size");
  const KdTree tree(points);
  const std::int64_t cells = targets.rows();
  const int d = int(targets.cols());
  std::vector<std::vector<Neighbour>> found(static_cast<std::size_t>(cells));
  Progress progress("candidates", std::uint64_t(cells));
#pragma omp parallel
  {
    std::vector<double> q(static_cast<std::size_t>(d));
#pragma omp for schedule(dynamic, 256)
    for (std::int64_t c = 0; c < cells; ++c) {
      progress.tick();
      if (!wanted[std::size_t(c)]) continue;
      for (int j = 0; j < d; ++j) q[j] = targets(c, j);
      std::vector<Neighbour> near = tree.nearest(q.data(), options.k);
      if (options.radius > 0) {
        const std::vector<Neighbour> ball = tree.within(q.data(), options.radius);
        std::vector<Neighbour> merged;
        merged.reserve(near.size() + ball.size());
        std::merge(near.begin(), near.end(), ball.begin(), ball.end(), std::back_inserter(merged), closer);
        merged.erase(std::unique(merged.begin(), merged.end(),
                                 [](const Neighbour& a, const Neighbour& b) { return a.index == b.index; }),
                     merged.end());
        near.swap(merged);
      }
      found[std::size_t(c)] = std::move(near);
    }
  }
  progress.done();
  CellCandidates out;
  out.offsets.assign(std::size_t(cells) + 1, 0);
  for (std::int64_t c = 0; c < cells; ++c) out.offsets[c + 1] = out.offsets[c] + std::int64_t(found[c].size());
  out.structure.reserve(std::size_t(out.offsets.back()));
  out.distance.reserve(std::size_t(out.offsets.back()));
  for (auto& list : found) {
    for (const Neighbour& n : list) out.structure.push_back(n.index), out.distance.push_back(std::sqrt(n.distance2));
    std::vector<Neighbour>().swap(list);
  }
  return out;
}

}  // namespace msfab
