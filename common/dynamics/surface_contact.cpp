#include "dynamics/surface_contact.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

namespace msfab {

namespace {

Vec3 quad_point(const std::array<Vec3, 4>& x, double s, double t) {
  return (1 - s) * (1 - t) * x[0] + s * (1 - t) * x[1] + s * t * x[2] + (1 - s) * t * x[3];
}

Vec3 quad_ds(const std::array<Vec3, 4>& x, double t) { return (1 - t) * (x[1] - x[0]) + t * (x[2] - x[3]); }
Vec3 quad_dt(const std::array<Vec3, 4>& x, double s) { return (1 - s) * (x[3] - x[0]) + s * (x[2] - x[1]); }

std::array<double, 4> bilinear_weights(double s, double t) {
  return {(1 - s) * (1 - t), s * (1 - t), s * t, (1 - s) * t};
}

// Parameter slack of the closest point: a node over the edge shared by two
// faces must be claimed by at least one of them despite round-off.
constexpr double kInsideTolerance = 1e-6;

// Integer cells of a uniform grid over the items' boxes (cell size: the
// largest box extent); the lookup is a sorted (cell, item) list,
// deterministic and compact.
class BoxGrid {
 public:
  BoxGrid(const std::vector<Vec3>& lo, const std::vector<Vec3>& hi) {
    double largest = 0;
    Vec3 all_lo = Vec3::Constant(INFINITY), all_hi = Vec3::Constant(-INFINITY);
    for (size_t i = 0; i < lo.size(); ++i) {
      largest = std::max(largest, (hi[i] - lo[i]).maxCoeff());
      all_lo = all_lo.cwiseMin(lo[i]);
      all_hi = all_hi.cwiseMax(hi[i]);
    }
    origin_ = all_lo;
    size_ = std::max(largest, 1e-300);
    for (int a = 0; a < 3; ++a) dims_(a) = std::max(1, static_cast<int>(std::ceil((all_hi(a) - all_lo(a)) / size_)));
    for (size_t i = 0; i < lo.size(); ++i)
      for_cells(lo[i], hi[i], [&](long long c) { cells_.emplace_back(c, static_cast<int>(i)); });
    std::sort(cells_.begin(), cells_.end());
  }

  // The items whose cells meet the box [lo, hi], sorted and unique.
  void query(const Vec3& lo, const Vec3& hi, std::vector<int>& items) const {
    items.clear();
    for_cells(lo, hi, [&](long long c) {
      auto it = std::lower_bound(cells_.begin(), cells_.end(), std::make_pair(c, -1));
      for (; it != cells_.end() && it->first == c; ++it) items.push_back(it->second);
    });
    std::sort(items.begin(), items.end());
    items.erase(std::unique(items.begin(), items.end()), items.end());
  }

 private:
  Eigen::Array3i coords(const Vec3& x) const {
    Eigen::Array3i c;
    for (int a = 0; a < 3; ++a)
      c(a) = std::clamp(static_cast<int>(std::floor((x(a) - origin_(a)) / size_)), 0, dims_(a) - 1);
    return c;
  }
  template <class Visit>
  void for_cells(const Vec3& lo, const Vec3& hi, Visit visit) const {
    const Eigen::Array3i a = coords(lo), b = coords(hi);
    for (int z = a.z(); z <= b.z(); ++z)
      for (int y = a.y(); y <= b.y(); ++y)
        for (int x = a.x(); x <= b.x(); ++x) visit((static_cast<long long>(z) * dims_.y() + y) * dims_.x() + x);
  }

  Vec3 origin_;
  double size_ = 1;
  Eigen::Array3i dims_;
  std::vector<std::pair<long long, int>> cells_;
};

// The box swept by `nodes` from `start` to `end`, grown by `inflate`.
template <class Nodes>
void swept_box(const Nodes& nodes, const VecX& start, const VecX& end, double inflate, Vec3& lo, Vec3& hi) {
  lo = Vec3::Constant(INFINITY);
  hi = Vec3::Constant(-INFINITY);
  for (int node : nodes)
    for (const VecX* x : {&start, &end}) {
      lo = lo.cwiseMin(x->segment<3>(3 * node));
      hi = hi.cwiseMax(x->segment<3>(3 * node));
    }
  lo.array() -= inflate;
  hi.array() += inflate;
}

bool boxes_overlap(const Vec3& lo_a, const Vec3& hi_a, const Vec3& lo_b, const Vec3& hi_b) {
  return !((lo_a.array() > hi_b.array()).any() || (hi_a.array() < lo_b.array()).any());
}

// Outward normal (not normalized) of a boundary quad at `x`, area-weighted.
Vec3 face_area_normal(const std::array<int, 4>& quad, const VecX& x) {
  return (x.segment<3>(3 * quad[2]) - x.segment<3>(3 * quad[0]))
      .cross(x.segment<3>(3 * quad[3]) - x.segment<3>(3 * quad[1]));
}

// Parameter slack of edge-edge closest points: at an end point (within
// this fraction of the edge) the vertex-face test applies.
constexpr double kEdgeInteriorMargin = 1e-6;
// Edges closer to parallel than this sine (about 3 degrees) have no
// well-defined common normal.
constexpr double kEdgeMinSine = 0.05;
// Each edge's outward normal must face the other edge by at least this
// cosine. A vertical edge standing on a flat face meets the face's edges
// at its end point with a horizontal common normal, perpendicular to the
// face's normal: its lines cross as it slides, though nothing penetrates.
constexpr double kEdgeMinFacing = 0.25;

}  // namespace

QuadProjection project_to_quad(const std::array<Vec3, 4>& x, const Vec3& p, double tolerance) {
  double s = 0.5, t = 0.5;
  for (int it = 0; it < 8; ++it) {
    const Vec3 r = quad_point(x, s, t) - p;
    const Vec3 xs = quad_ds(x, t), xt = quad_dt(x, s);
    Eigen::Matrix2d JtJ;
    JtJ << xs.dot(xs), xs.dot(xt), xs.dot(xt), xt.dot(xt);
    const Eigen::Vector2d step = JtJ.ldlt().solve(-Eigen::Vector2d(xs.dot(r), xt.dot(r)));
    if (!step.allFinite()) break;
    s += step(0);
    t += step(1);
    if (step.cwiseAbs().maxCoeff() < 1e-12) break;
  }
  QuadProjection q;
  q.inside = s >= -tolerance && s <= 1 + tolerance && t >= -tolerance && t <= 1 + tolerance;
  q.s = std::clamp(s, 0.0, 1.0);
  q.t = std::clamp(t, 0.0, 1.0);
  return q;
}

Vec3 quad_normal(const std::array<Vec3, 4>& x, double s, double t) {
  return quad_ds(x, t).cross(quad_dt(x, s)).normalized();
}

bool closest_line_parameters(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1, double min_sine,
                             double& alpha, double& beta) {
  const Vec3 ea = a1 - a0, eb = b1 - b0, r = a0 - b0;
  const double aa = ea.dot(ea), bb = eb.dot(eb), ab = ea.dot(eb);
  const double det = aa * bb - ab * ab;  // |e_a x e_b|^2
  if (!(det > min_sine * min_sine * aa * bb)) return false;
  // Stationarity of |a0 + alpha e_a - b0 - beta e_b|^2 in alpha and beta.
  const double ra = r.dot(ea), rb = r.dot(eb);
  alpha = (ab * rb - bb * ra) / det;
  beta = (aa * rb - ab * ra) / det;
  return true;
}

BoundarySurface::BoundarySurface(HexBoundary boundary, std::vector<int> nodes)
    : boundary_(std::move(boundary)), nodes_(std::move(nodes)) {
  std::vector<std::pair<std::array<int, 2>, int>> sides;
  for (int f = 0; f < static_cast<int>(boundary_.faces.size()); ++f)
    for (int i = 0; i < 4; ++i) {
      const int a = boundary_.faces[f][i], b = boundary_.faces[f][(i + 1) % 4];
      sides.push_back({{std::min(a, b), std::max(a, b)}, f});
    }
  std::sort(sides.begin(), sides.end());
  for (const auto& [pair, face] : sides) {
    if (edges_.empty() || edges_.back().nodes != pair) edges_.push_back({pair, {}});
    edges_.back().faces.push_back(face);
  }
}

std::vector<NodeFaceContact> BoundarySurface::find(const VecX& start, const VecX& end, double margin,
                                                   double depth_limit) const {
  std::vector<NodeFaceContact> found;
  const int num_faces = static_cast<int>(boundary_.faces.size());
  if (num_faces == 0 || nodes_.empty()) return found;

  // Swept boxes of the faces, inflated by the margin.
  const double inflate = std::max(margin, 0.0);
  std::vector<Vec3> lo(num_faces), hi(num_faces);
  for (int f = 0; f < num_faces; ++f) swept_box(boundary_.faces[f], start, end, inflate, lo[f], hi[f]);
  const BoxGrid grid(lo, hi);

  // Vertex normals at `end` (area-weighted face normals): a node only
  // touches a face that its own surface faces.
  std::vector<Vec3> vertex_normal(end.size() / 3, Vec3::Zero());
  for (const auto& quad : boundary_.faces) {
    for (int node : quad) vertex_normal[node] += face_area_normal(quad, end);
  }

  std::vector<int> faces;
  std::vector<NodeFaceContact> for_node;
  for (int node : nodes_) {
    const Vec3 p0 = start.segment<3>(3 * node), p1 = end.segment<3>(3 * node);
    grid.query(p0.cwiseMin(p1), p0.cwiseMax(p1), faces);

    for_node.clear();
    for (int f : faces) {
      const auto& quad = boundary_.faces[f];
      if (std::find(quad.begin(), quad.end(), node) != quad.end()) continue;
      if (!boxes_overlap(p0.cwiseMin(p1), p0.cwiseMax(p1), lo[f], hi[f])) continue;
      std::array<Vec3, 4> x1, x0;
      for (int i = 0; i < 4; ++i) {
        x0[i] = start.segment<3>(3 * quad[i]);
        x1[i] = end.segment<3>(3 * quad[i]);
      }
      const QuadProjection proj = project_to_quad(x1, p1, kInsideTolerance);
      if (!proj.inside) continue;
      NodeFaceContact c;
      c.node = node;
      c.face = f;
      c.weights = bilinear_weights(proj.s, proj.t);
      c.normal = quad_normal(x1, proj.s, proj.t);
      if (!c.normal.allFinite() || !(vertex_normal[node].dot(c.normal) < 0)) continue;
      c.gap_end = c.normal.dot(p1 - quad_point(x1, proj.s, proj.t));
      c.gap_start = c.normal.dot(p0 - quad_point(x0, proj.s, proj.t));
      if (c.gap_end < margin && c.gap_start >= -depth_limit) for_node.push_back(c);
    }
    // Nearest first; a face whose normal repeats a kept one adds no new
    // direction (a node over the edge between two coplanar faces).
    std::stable_sort(for_node.begin(), for_node.end(), [](const NodeFaceContact& l, const NodeFaceContact& r) {
      return std::abs(l.gap_end) < std::abs(r.gap_end);
    });
    const size_t first = found.size();
    for (const NodeFaceContact& c : for_node) {
      bool repeated = false;
      for (size_t k = first; k < found.size(); ++k) repeated = repeated || found[k].normal.dot(c.normal) > 0.9;
      if (!repeated) found.push_back(c);
    }
    std::sort(found.begin() + static_cast<std::ptrdiff_t>(first), found.end(),
              [](const NodeFaceContact& l, const NodeFaceContact& r) { return l.face < r.face; });
  }
  return found;
}

std::vector<EdgeEdgeContact> BoundarySurface::find_edges(const VecX& start, const VecX& end, double margin,
                                                         double depth_limit) const {
  std::vector<EdgeEdgeContact> found;
  const int num_edges = static_cast<int>(edges_.size());
  if (num_edges == 0) return found;
  std::vector<char> moves(start.size() / 3, 0);
  for (int node : nodes_) moves[node] = 1;

  const double inflate = std::max(margin, 0.0);
  std::vector<Vec3> lo(num_edges), hi(num_edges);
  for (int e = 0; e < num_edges; ++e) swept_box(edges_[e].nodes, start, end, inflate, lo[e], hi[e]);
  const BoxGrid grid(lo, hi);

  // Outward unit edge normals at `end`: along the sum of the bordering
  // faces' unit normals.
  std::vector<Vec3> face_normal(boundary_.faces.size());
  for (size_t f = 0; f < boundary_.faces.size(); ++f)
    face_normal[f] = face_area_normal(boundary_.faces[f], end).normalized();
  std::vector<Vec3> edge_normal(num_edges, Vec3::Zero());
  for (int e = 0; e < num_edges; ++e)
    for (int f : edges_[e].faces) edge_normal[e] += face_normal[f];
  for (Vec3& n : edge_normal) n.normalize();

  std::vector<int> near;
  for (int a = 0; a < num_edges; ++a) {
    const auto& na = edges_[a].nodes;
    grid.query(lo[a], hi[a], near);
    for (int b : near) {
      if (b <= a) continue;
      const auto& nb = edges_[b].nodes;
      if (na[0] == nb[0] || na[0] == nb[1] || na[1] == nb[0] || na[1] == nb[1]) continue;
      if (!(moves[na[0]] || moves[na[1]] || moves[nb[0]] || moves[nb[1]])) continue;
      if (!boxes_overlap(lo[a], hi[a], lo[b], hi[b])) continue;
      auto at = [](const VecX& x, int node) { return Vec3(x.segment<3>(3 * node)); };
      const Vec3 a0 = at(end, na[0]), a1 = at(end, na[1]), b0 = at(end, nb[0]), b1 = at(end, nb[1]);
      EdgeEdgeContact c;
      if (!closest_line_parameters(a0, a1, b0, b1, kEdgeMinSine, c.alpha, c.beta)) continue;
      if (c.alpha <= kEdgeInteriorMargin || c.alpha >= 1 - kEdgeInteriorMargin || c.beta <= kEdgeInteriorMargin ||
          c.beta >= 1 - kEdgeInteriorMargin)
        continue;
      c.normal = (a1 - a0).cross(b1 - b0).normalized();
      if ((edge_normal[b] - edge_normal[a]).dot(c.normal) < 0) c.normal = -c.normal;
      if (!(edge_normal[a].dot(c.normal) < -kEdgeMinFacing && edge_normal[b].dot(c.normal) > kEdgeMinFacing)) continue;
      auto relative = [&](const VecX& x) {
        return Vec3((1 - c.alpha) * at(x, na[0]) + c.alpha * at(x, na[1]) - (1 - c.beta) * at(x, nb[0]) -
                    c.beta * at(x, nb[1]));
      };
      c.gap_end = c.normal.dot(relative(end));
      c.gap_start = c.normal.dot(relative(start));
      if (!(c.gap_end < margin && c.gap_start >= -depth_limit)) continue;
      c.edge_a = a;
      c.edge_b = b;
      found.push_back(c);
    }
  }
  return found;
}

}  // namespace msfab
