#include "fem/surface_voxelizer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <utility>

namespace msfab {
namespace {

struct Point2 {
  double x, y;
};

bool lexicographically_less(const Point2& a, const Point2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

// Twice the signed area of (a, b, p): positive when p lies left of a -> b.
// Evaluated with the endpoints in canonical order and negated when they were
// swapped, so that edge (a, b) and edge (b, a) give exactly opposite values.
double edge_function(const Point2& a, const Point2& b, const Point2& p) {
  const bool swapped = lexicographically_less(b, a);
  const Point2& s = swapped ? b : a;
  const Point2& t = swapped ? a : b;
  const double value = (t.x - s.x) * (p.y - s.y) - (t.y - s.y) * (p.x - s.x);
  return swapped ? -value : value;
}

// The top-left rule for a counter-clockwise triangle (y up): a point exactly
// on an edge belongs to the triangle when the edge is a left edge (it runs
// downwards) or a top edge (horizontal, running towards -x). Of the two
// triangles sharing an edge, which traverse it in opposite directions,
// exactly one owns it.
bool owns_edge(const Point2& a, const Point2& b) { return b.y < a.y || (b.y == a.y && b.x < a.x); }

bool covers(const Point2& a, const Point2& b, const Point2& p) {
  const double e = edge_function(a, b, p);
  return e > 0 || (e == 0 && owns_edge(a, b));
}

}  // namespace

TriangleSurface merge_equal_vertices(const TriangleSurface& surface) {
  TriangleSurface out;
  std::map<std::array<double, 3>, int> index_of;
  std::vector<int> remap(surface.vertices.size());
  for (std::size_t v = 0; v < surface.vertices.size(); ++v) {
    const Vec3& p = surface.vertices[v];
    const auto [it, added] =
        index_of.emplace(std::array<double, 3>{p.x(), p.y(), p.z()}, static_cast<int>(out.vertices.size()));
    if (added) out.vertices.push_back(p);
    remap[v] = it->second;
  }
  out.triangles.reserve(surface.triangles.size());
  for (const auto& t : surface.triangles) out.triangles.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
  return out;
}

SurfaceClosure check_closure(const TriangleSurface& surface) {
  SurfaceClosure result;
  // Net count of each undirected edge's traversals: +1 for (a, b) with a < b,
  // -1 for (b, a). A closed, consistently oriented surface nets zero on each.
  std::map<std::pair<int, int>, int> net;
  for (const auto& t : surface.triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) {
      ++result.degenerate_triangles;
      continue;
    }
    for (int e = 0; e < 3; ++e) {
      const int a = t[e], b = t[(e + 1) % 3];
      net[{std::min(a, b), std::max(a, b)}] += a < b ? 1 : -1;
    }
  }
  for (const auto& [edge, count] : net) {
    if (count == 0) continue;
    result.unmatched_edges += std::abs(count);
    if (result.example_edge[0] < 0) result.example_edge = {edge.first, edge.second};
  }
  return result;
}

std::array<Vec3, 2> bounding_box(const TriangleSurface& surface) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Vec3& p : surface.vertices) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return {lo, hi};
}

std::vector<char> voxels_inside(const VoxelGrid& grid, const TriangleSurface& surface) {
  const double h = grid.voxel_size;
  // Crossings of each voxel-centre column (i, j): height and sign.
  std::vector<std::vector<std::pair<double, int>>> crossings(std::size_t(grid.nx) * grid.ny);
  const auto column_range = [&](double lo, double hi, double origin, int n) {
    // Columns whose centre coordinate origin + (c + 1/2) h lies in [lo, hi].
    const int first = std::max(0, static_cast<int>(std::ceil((lo - origin) / h - 0.5)) - 1);
    const int last = std::min(n - 1, static_cast<int>(std::floor((hi - origin) / h - 0.5)) + 1);
    return std::pair<int, int>{first, last};
  };
  for (const auto& t : surface.triangles) {
    const Vec3 &A = surface.vertices[t[0]], &B = surface.vertices[t[1]], &C = surface.vertices[t[2]];
    Point2 a{A.x(), A.y()}, b{B.x(), B.y()}, c{C.x(), C.y()};
    double za = A.z(), zb = B.z(), zc = C.z();
    const double area = edge_function(a, b, c);
    if (area == 0) continue;  // seen edge-on from the column: the neighbours carry the crossing
    int sign = 1;             // normal pointing up: the column leaves the volume here
    if (area < 0) {           // make it counter-clockwise; the normal points down
      std::swap(b, c);
      std::swap(zb, zc);
      sign = -1;
    }
    const auto [i0, i1] = column_range(std::min({a.x, b.x, c.x}), std::max({a.x, b.x, c.x}), grid.origin.x(), grid.nx);
    const auto [j0, j1] = column_range(std::min({a.y, b.y, c.y}), std::max({a.y, b.y, c.y}), grid.origin.y(), grid.ny);
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const Point2 p{grid.origin.x() + (i + 0.5) * h, grid.origin.y() + (j + 0.5) * h};
        if (!covers(a, b, p) || !covers(b, c, p) || !covers(c, a, p)) continue;
        // Barycentric weights of the opposite edges give the crossing height.
        const double wa = edge_function(b, c, p), wb = edge_function(c, a, p), wc = edge_function(a, b, p);
        const double z = (wa * za + wb * zb + wc * zc) / (wa + wb + wc);
        crossings[std::size_t(i) + std::size_t(grid.nx) * j].emplace_back(z, sign);
      }
  }
  std::vector<char> inside(grid.size(), 0);
  for (int j = 0; j < grid.ny; ++j)
    for (int i = 0; i < grid.nx; ++i) {
      auto& list = crossings[std::size_t(i) + std::size_t(grid.nx) * j];
      if (list.empty()) continue;
      std::sort(list.begin(), list.end());
      // Winding number of a point = sum of the signs of the crossings above
      // it; below every crossing that is the column's total.
      int winding = 0;
      for (const auto& crossing : list) winding += crossing.second;
      std::size_t next = 0;
      for (int k = 0; k < grid.nz; ++k) {
        const double z = grid.origin.z() + (k + 0.5) * h;
        while (next < list.size() && list[next].first <= z) winding -= list[next++].second;
        if (winding != 0) inside[grid.index(i, j, k)] = 1;
      }
    }
  return inside;
}

long long paint_surface(VoxelGrid& grid, const TriangleSurface& surface, int id) {
  const std::vector<char> inside = voxels_inside(grid, surface);
  long long count = 0;
  for (std::size_t v = 0; v < inside.size(); ++v)
    if (inside[v]) {
      grid.ids[v] = id;
      ++count;
    }
  return count;
}

}  // namespace msfab
