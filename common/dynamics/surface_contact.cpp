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

// Integer cells of a uniform grid over the faces' swept boxes; the lookup is
// a sorted (cell, face) list, deterministic and compact.
struct CellGrid {
  Vec3 origin;
  double size = 1;
  Eigen::Array3i dims;
  long long cell(const Eigen::Array3i& c) const {
    return (static_cast<long long>(c.z()) * dims.y() + c.y()) * dims.x() + c.x();
  }
  Eigen::Array3i coords(const Vec3& x) const {
    Eigen::Array3i c;
    for (int a = 0; a < 3; ++a)
      c(a) = std::clamp(static_cast<int>(std::floor((x(a) - origin(a)) / size)), 0, dims(a) - 1);
    return c;
  }
};

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

BoundarySurface::BoundarySurface(HexBoundary boundary, std::vector<int> nodes)
    : boundary_(std::move(boundary)), nodes_(std::move(nodes)) {}

std::vector<NodeFaceContact> BoundarySurface::find(const VecX& start, const VecX& end, double margin,
                                                   double depth_limit) const {
  std::vector<NodeFaceContact> found;
  const int num_faces = static_cast<int>(boundary_.faces.size());
  if (num_faces == 0 || nodes_.empty()) return found;

  // Swept boxes of the faces, inflated by the margin.
  const double inflate = std::max(margin, 0.0);
  std::vector<Vec3> lo(num_faces), hi(num_faces);
  double largest = 0;
  Vec3 all_lo = Vec3::Constant(INFINITY), all_hi = Vec3::Constant(-INFINITY);
  for (int f = 0; f < num_faces; ++f) {
    lo[f] = Vec3::Constant(INFINITY);
    hi[f] = Vec3::Constant(-INFINITY);
    for (int node : boundary_.faces[f]) {
      for (const VecX* x : {&start, &end}) {
        lo[f] = lo[f].cwiseMin(x->segment<3>(3 * node));
        hi[f] = hi[f].cwiseMax(x->segment<3>(3 * node));
      }
    }
    lo[f].array() -= inflate;
    hi[f].array() += inflate;
    largest = std::max(largest, (hi[f] - lo[f]).maxCoeff());
    all_lo = all_lo.cwiseMin(lo[f]);
    all_hi = all_hi.cwiseMax(hi[f]);
  }
  CellGrid grid;
  grid.origin = all_lo;
  grid.size = std::max(largest, 1e-300);
  for (int a = 0; a < 3; ++a)
    grid.dims(a) = std::max(1, static_cast<int>(std::ceil((all_hi(a) - all_lo(a)) / grid.size)));
  std::vector<std::pair<long long, int>> cells;
  for (int f = 0; f < num_faces; ++f) {
    const Eigen::Array3i a = grid.coords(lo[f]), b = grid.coords(hi[f]);
    for (int z = a.z(); z <= b.z(); ++z)
      for (int y = a.y(); y <= b.y(); ++y)
        for (int x = a.x(); x <= b.x(); ++x) cells.emplace_back(grid.cell({x, y, z}), f);
  }
  std::sort(cells.begin(), cells.end());

  // Vertex normals at `end` (area-weighted face normals): a node only
  // touches a face that its own surface faces.
  std::vector<Vec3> vertex_normal(end.size() / 3, Vec3::Zero());
  for (const auto& quad : boundary_.faces) {
    const Vec3 n = (end.segment<3>(3 * quad[2]) - end.segment<3>(3 * quad[0]))
                       .cross(end.segment<3>(3 * quad[3]) - end.segment<3>(3 * quad[1]));
    for (int node : quad) vertex_normal[node] += n;
  }

  std::vector<int> faces;
  std::vector<NodeFaceContact> for_node;
  for (int node : nodes_) {
    const Vec3 p0 = start.segment<3>(3 * node), p1 = end.segment<3>(3 * node);
    const Eigen::Array3i a = grid.coords(p0.cwiseMin(p1)), b = grid.coords(p0.cwiseMax(p1));
    faces.clear();
    for (int z = a.z(); z <= b.z(); ++z)
      for (int y = a.y(); y <= b.y(); ++y)
        for (int x = a.x(); x <= b.x(); ++x) {
          const long long c = grid.cell({x, y, z});
          auto it = std::lower_bound(cells.begin(), cells.end(), std::make_pair(c, -1));
          for (; it != cells.end() && it->first == c; ++it) faces.push_back(it->second);
        }
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());

    for_node.clear();
    for (int f : faces) {
      const auto& quad = boundary_.faces[f];
      if (std::find(quad.begin(), quad.end(), node) != quad.end()) continue;
      if ((p0.cwiseMin(p1).array() > hi[f].array()).any() || (p0.cwiseMax(p1).array() < lo[f].array()).any()) continue;
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
    std::stable_sort(for_node.begin(), for_node.end(),
                     [](const NodeFaceContact& l, const NodeFaceContact& r) { return std::abs(l.gap_end) < std::abs(r.gap_end); });
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

}  // namespace msfab
