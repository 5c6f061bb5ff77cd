#include "families/skeleton.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <numeric>
#include <set>
#include <string>
#include <utility>

#include "core/errors.hpp"
#include "families/cell_symmetry.hpp"

namespace msfab {
namespace {

void require_cube(const VoxelGrid& c, const char* what) {
  if (c.nx != c.ny || c.ny != c.nz || c.nx < 3)
    throw InputError(std::string(what) + ": needs a cubic n x n x n cell with n >= 3, got " + std::to_string(c.nx) +
                     " x " + std::to_string(c.ny) + " x " + std::to_string(c.nz));
  if (c.ids.size() != c.size() || c.size() != std::size_t(c.nx) * c.ny * c.nz)
    throw InputError(std::string(what) + ": the cell has " + std::to_string(c.ids.size()) + " voxel ids for " +
                     std::to_string(c.nx) + "^3 voxels");
}

// A 3x3x3 neighbourhood is a 27-bit mask; offset (dx, dy, dz) in
// {-1, 0, 1}^3 is bit (dx + 1) + 3 (dy + 1) + 9 (dz + 1); the centre is 13.
constexpr int kCentre = 13;
constexpr std::uint32_t kCentreBit = 1u << kCentre;
int offset_bit(int dx, int dy, int dz) { return (dx + 1) + 3 * (dy + 1) + 9 * (dz + 1); }

struct NeighbourhoodTables {
  std::array<std::uint32_t, 27> adjacent{};  // 26-neighbours of each position inside the 3x3x3 block, centre excluded
  // The 26 faces, edges and corners of the centre voxel's closed cube: the
  // neighbours that share each one, and its sign in the Euler
  // characteristic (+1 faces and corners, -1 edges).
  std::array<std::uint32_t, 26> sharing{};
  std::array<int, 26> sign{};
};

const NeighbourhoodTables& tables() {
  static const NeighbourhoodTables t = [] {
    NeighbourhoodTables t;
    for (int o = 0; o < 27; ++o) {
      const int p[3] = {o % 3 - 1, o / 3 % 3 - 1, o / 9 - 1};
      for (int q = 0; q < 27; ++q) {
        const int r[3] = {q % 3 - 1, q / 3 % 3 - 1, q / 9 - 1};
        const bool near = std::abs(p[0] - r[0]) <= 1 && std::abs(p[1] - r[1]) <= 1 && std::abs(p[2] - r[2]) <= 1;
        if (q != o && q != kCentre && near) t.adjacent[o] |= 1u << q;
      }
    }
    int cell = 0;
    for (int o = 0; o < 27; ++o) {
      if (o == kCentre) continue;
      // The boundary cell of the centre cube on the side s = offset o; the
      // voxels containing it are the offsets d with d_i in {0, s_i}.
      const int s[3] = {o % 3 - 1, o / 3 % 3 - 1, o / 9 - 1};
      const int nonzero = (s[0] != 0) + (s[1] != 0) + (s[2] != 0);
      std::uint32_t mask = 0;
      for (int dz = std::min(0, s[2]); dz <= std::max(0, s[2]); ++dz)
        for (int dy = std::min(0, s[1]); dy <= std::max(0, s[1]); ++dy)
          for (int dx = std::min(0, s[0]); dx <= std::max(0, s[0]); ++dx)
            if (dx || dy || dz) mask |= 1u << offset_bit(dx, dy, dz);
      t.sharing[cell] = mask;
      t.sign[cell] = nonzero == 2 ? -1 : 1;  // dimension 3 - nonzero
      ++cell;
    }
    return t;
  }();
  return t;
}

// Change of the Euler characteristic of the solid (a union of closed unit
// cubes, which is what 26-connectivity of solid means) when the centre
// voxel is added to its neighbours: the centre cube's own cells that no
// neighbour already covers, counted with alternating signs, less the cube.
int euler_change(std::uint32_t neighbours) {
  const auto& t = tables();
  int change = -1;
  for (int c = 0; c < 26; ++c)
    if (!(neighbours & t.sharing[c])) change += t.sign[c];
  return change;
}

// Number of 26-connected pieces of the given neighbours (centre excluded),
// stopping once more than `limit` are found.
int neighbour_pieces(std::uint32_t set, int limit) {
  const auto& t = tables();
  int pieces = 0;
  while (set) {
    if (++pieces > limit) return pieces;
    std::uint32_t frontier = set & (~set + 1);
    set &= ~frontier;
    while (frontier) {
      const int o = __builtin_ctz(frontier);
      frontier &= frontier - 1;
      const std::uint32_t reached = t.adjacent[o] & set;
      set &= ~reached;
      frontier |= reached;
    }
  }
  return pieces;
}

// A solid voxel may go when it is not an end point, deleting it keeps the
// Euler characteristic, and its solid neighbours stay one piece (Lee et
// al.'s simple-point test; the border condition of the caller rules out
// creating a cavity).
bool deletable(std::uint32_t neighbours) {
  const int count = __builtin_popcount(neighbours);
  if (count <= 1) return false;
  if (euler_change(neighbours) != 0) return false;
  return neighbour_pieces(neighbours, 1) == 1;
}

struct PeriodicCube {
  int n;
  std::vector<int> minus, plus;  // wrapped i - 1 and i + 1
  explicit PeriodicCube(int n_) : n(n_), minus(n_), plus(n_) {
    for (int i = 0; i < n; ++i) minus[i] = (i + n - 1) % n, plus[i] = (i + 1) % n;
  }
  int step(int i, int d) const { return d < 0 ? minus[i] : d > 0 ? plus[i] : i; }
  std::size_t index(int i, int j, int k) const { return std::size_t(i) + std::size_t(n) * (j + std::size_t(n) * k); }
  std::size_t neighbour(std::size_t v, int dx, int dy, int dz) const {
    const int i = int(v % n), j = int(v / n % n), k = int(v / (std::size_t(n) * n));
    return index(step(i, dx), step(j, dy), step(k, dz));
  }
  std::uint32_t gather(const std::vector<std::uint8_t>& solid, std::size_t v) const {
    const int i = int(v % n), j = int(v / n % n), k = int(v / (std::size_t(n) * n));
    std::uint32_t mask = 0;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          if (solid[index(step(i, dx), step(j, dy), step(k, dz))]) mask |= 1u << offset_bit(dx, dy, dz);
    return mask & ~kCentreBit;
  }
};

int count_pieces(const VoxelGrid& c, bool solid_wanted, bool full26, const char* what) {
  require_cube(c, what);
  const PeriodicCube cube(c.nx);
  std::vector<std::uint8_t> seen(c.size(), 0);
  std::vector<std::size_t> stack;
  int pieces = 0;
  for (std::size_t s = 0; s < c.size(); ++s) {
    if (seen[s] || (c.ids[s] != 0) != solid_wanted) continue;
    ++pieces;
    seen[s] = 1;
    stack.assign(1, s);
    while (!stack.empty()) {
      const std::size_t v = stack.back();
      stack.pop_back();
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int order = std::abs(dx) + std::abs(dy) + std::abs(dz);
            if (order == 0 || (!full26 && order > 1)) continue;
            const std::size_t w = cube.neighbour(v, dx, dy, dz);
            if (seen[w] || (c.ids[w] != 0) != solid_wanted) continue;
            seen[w] = 1;
            stack.push_back(w);
          }
    }
  }
  return pieces;
}

// The step from voxel coordinate a to its neighbour b along one axis.
int wrapped_step(int a, int b, int n) {
  const int d = b - a;
  return d > 1 ? d - n : d < -1 ? d + n : d;
}

std::array<int, 3> voxel_step(const SkeletonGraph& g, int u, int w) {
  const int n = g.n;
  const int a = g.voxel[u], b = g.voxel[w];
  return {wrapped_step(a % n, b % n, n), wrapped_step(a / n % n, b / n % n, n),
          wrapped_step(a / (n * n), b / (n * n), n)};
}

Vec3 step_vector(const SkeletonGraph& g, int u, int w) {
  const auto d = voxel_step(g, u, w);
  return Vec3(d[0], d[1], d[2]) / double(g.n);
}

// Nodes of the skeleton graph: end vertices (degree 1) and junctions.
// Junction vertices (degree >= 3, or marked `joined`) that touch form one
// node, placed at their centroid.
struct Nodes {
  std::vector<int> node;      // per vertex: its node, -1 for a vertex inside a path
  std::vector<int> kind;      // per node: 1 end, 2 junction
  std::vector<Vec3> to_node;  // per vertex of a node: unwrapped offset to the node's point
  std::vector<std::vector<int>> members;
};

Nodes find_nodes(const SkeletonGraph& g, const std::vector<std::uint8_t>& joined) {
  const int nv = static_cast<int>(g.voxel.size());
  auto junction = [&](int v) { return g.neighbours[v].size() >= 3 || joined[v]; };
  Nodes out;
  out.node.assign(nv, -1);
  out.to_node.assign(nv, Vec3::Zero());
  for (int s = 0; s < nv; ++s) {
    const int degree = static_cast<int>(g.neighbours[s].size());
    if (out.node[s] >= 0 || degree == 0 || (degree == 2 && !joined[s])) continue;
    const int id = static_cast<int>(out.kind.size());
    out.kind.push_back(junction(s) ? 2 : 1);
    out.node[s] = id;
    std::vector<int> members{s};
    std::vector<Vec3> at{Vec3::Zero()};
    if (junction(s))
      for (std::size_t q = 0; q < members.size(); ++q)
        for (int w : g.neighbours[members[q]])
          if (junction(w) && out.node[w] < 0) {
            out.node[w] = id;
            members.push_back(w);
            at.push_back(at[q] + step_vector(g, members[q], w));
          }
    Vec3 centroid = Vec3::Zero();
    for (const Vec3& p : at) centroid += p;
    centroid /= double(at.size());
    for (std::size_t q = 0; q < members.size(); ++q) out.to_node[members[q]] = centroid - at[q];
    out.members.push_back(std::move(members));
  }
  return out;
}

// A path with the nodes it joins (-1 for a loop without nodes).
struct TracedPath {
  SkeletonPath path;
  std::vector<int> vertices;  // the degree-2 vertices it runs through, and an end vertex at either end
  int start = -1, end = -1;
};

std::vector<TracedPath> trace_paths(const SkeletonGraph& g, const Nodes& nodes) {
  const int nv = static_cast<int>(g.voxel.size());
  const auto& node = nodes.node;
  std::vector<TracedPath> out;
  std::set<std::pair<int, int>> used;  // directed edges already walked
  std::vector<std::uint8_t> on_path(nv, 0);
  auto walk = [&](int from, int first, TracedPath& t) {
    int prev = from, cur = first;
    Vec3 p = g.position[from] + step_vector(g, from, first);
    used.insert({from, first});  // a direct node-to-node edge is walked once
    while (true) {
      if (node[cur] >= 0) {
        used.insert({cur, prev});
        if (nodes.kind[node[cur]] == 1) t.vertices.push_back(cur);
        t.path.points.push_back(p + nodes.to_node[cur]);
        t.end = node[cur];
        return;
      }
      on_path[cur] = 1;
      t.vertices.push_back(cur);
      t.path.points.push_back(p);
      const auto& nb = g.neighbours[cur];
      const int next = nb[0] == prev ? nb[1] : nb[0];
      p += step_vector(g, cur, next);
      prev = cur;
      cur = next;
      if (t.path.closed && cur == t.vertices.front()) {
        t.path.points.push_back(p);
        return;
      }
    }
  };
  for (int u = 0; u < nv; ++u) {
    if (node[u] < 0) continue;
    for (int w : g.neighbours[u]) {
      if (node[w] == node[u] || used.count({u, w})) continue;
      TracedPath t;
      t.start = node[u];
      if (nodes.kind[node[u]] == 1) t.vertices.push_back(u);
      t.path.points.push_back(g.position[u] + nodes.to_node[u]);
      walk(u, w, t);
      out.push_back(std::move(t));
    }
  }
  // What is left of the path vertices are loops without nodes.
  for (int u = 0; u < nv; ++u) {
    if (node[u] >= 0 || g.neighbours[u].size() != 2 || on_path[u]) continue;
    TracedPath t;
    t.path.closed = true;
    on_path[u] = 1;
    t.vertices.push_back(u);
    t.path.points.push_back(g.position[u]);
    walk(u, g.neighbours[u][0], t);
    out.push_back(std::move(t));
  }
  return out;
}

double polyline_length(const std::vector<Vec3>& points) {
  double length = 0;
  for (std::size_t i = 1; i < points.size(); ++i) length += (points[i] - points[i - 1]).norm();
  return length;
}

// Distance (unit-cell units) from the centre of each given voxel to the
// nearest void voxel centre, searched in growing cubic shells.
std::vector<double> inscribed_radius(const VoxelGrid& cell, const std::vector<int>& voxels) {
  const int n = cell.nx;
  std::vector<double> out(voxels.size());
#pragma omp parallel for schedule(dynamic, 8) if (voxels.size() >= 1024)
  for (int q = 0; q < int(voxels.size()); ++q) {
    const int v = voxels[q];
    const int i = v % n, j = v / n % n, k = v / (n * n);
    int best2 = n * n;  // squared voxel distance
    for (int r = 1; r <= n / 2 && r * r < best2; ++r)
      for (int dz = -r; dz <= r; ++dz)
        for (int dy = -r; dy <= r; ++dy)
          for (int dx = -r; dx <= r; ++dx) {
            if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != r) continue;
            const int d2 = dx * dx + dy * dy + dz * dz;
            if (d2 >= best2) continue;
            if (!cell.at(((i + dx) % n + n) % n, ((j + dy) % n + n) % n, ((k + dz) % n + n) % n)) best2 = d2;
          }
    out[q] = std::sqrt(double(best2)) / n;
  }
  return out;
}

double point_segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

// The image of a segment that the symmetries and lattice translations
// bring into the fundamental domain by its midpoint, ends in
// lexicographic order.
Segment canonical_image(const Segment& s) {
  Segment c = s;
  Vec3 m = 0.5 * (s.a + s.b);
  for (int i = 0; i < 3; ++i) {
    const double shift = std::floor(m[i]);
    c.a[i] -= shift, c.b[i] -= shift, m[i] -= shift;
    if (m[i] > 0.5) c.a[i] = 1.0 - c.a[i], c.b[i] = 1.0 - c.b[i], m[i] = 1.0 - m[i];
  }
  std::array<int, 3> axis{0, 1, 2};
  std::stable_sort(axis.begin(), axis.end(), [&](int p, int q) { return m[p] < m[q]; });
  const Segment folded = c;
  for (int i = 0; i < 3; ++i) c.a[i] = folded.a[axis[i]], c.b[i] = folded.b[axis[i]];
  if (std::lexicographical_compare(c.b.data(), c.b.data() + 3, c.a.data(), c.a.data() + 3)) std::swap(c.a, c.b);
  return c;
}

// Distance from p to the nearest image of k under the cube symmetries and
// lattice translations; with `moved_only`, k itself does not count.
double distance_to_images(const Vec3& p, const Segment& k, bool moved_only = false) {
  double best = std::numeric_limits<double>::infinity();
  const auto& symmetries = cell_symmetries();
  for (std::size_t s = 0; s < symmetries.size(); ++s) {
    const Mat3& S = symmetries[s];
    // The symmetries are orthogonal and fix the centre, so the distance to
    // an image of k is the distance from the inverse image of p to k.
    const Vec3 q = apply_cell_symmetry(S.transpose(), p);
    const Vec3 mid = 0.5 * (k.a + k.b);
    const Vec3 base = (q - mid).array().round().matrix();
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const Vec3 shift = base + Vec3(dx, dy, dz);
          if (moved_only && s == 0 && shift.isZero()) continue;  // the identity comes first
          best = std::min(best, point_segment_distance(q - shift, k.a, k.b));
        }
  }
  return best;
}

// Whether every point of s lies within tol of an image of a kept segment,
// checked at points no more than tol / 2 apart.
bool covered(const Segment& s, const std::vector<Segment>& kept, double tol, bool moved_only = false) {
  const int pieces = std::max(1, static_cast<int>(std::ceil((s.b - s.a).norm() / (0.5 * std::max(tol, 1e-6)))));
  for (int i = 0; i <= pieces; ++i) {
    const Vec3 p = s.a + (s.b - s.a) * (double(i) / pieces);
    bool near = false;
    for (const Segment& k : kept) near = near || distance_to_images(p, k, moved_only) <= tol;
    if (!near) return false;
  }
  return true;
}

// Where s crosses a mirror plane of the periodic cubic cell, as fractions
// of the way from a to b strictly inside (0, 1): the planes x_i = k / 2,
// x_i - x_j = k and x_i + x_j = k for integers k.
std::vector<double> mirror_crossings(const Segment& s) {
  std::vector<double> t;
  auto crossings = [&](double from, double to, double spacing) {
    if (std::abs(to - from) < 1e-12) return;  // along the plane
    const double lo = std::min(from, to), hi = std::max(from, to);
    for (double k = std::ceil(lo / spacing); k * spacing <= hi; k += 1) {
      const double f = (k * spacing - from) / (to - from);
      if (f > 1e-9 && f < 1 - 1e-9) t.push_back(f);
    }
  };
  for (int i = 0; i < 3; ++i) {
    crossings(s.a[i], s.b[i], 0.5);
    for (int j = i + 1; j < 3; ++j) {
      crossings(s.a[i] - s.a[j], s.b[i] - s.b[j], 1.0);
      crossings(s.a[i] + s.a[j], s.b[i] + s.b[j], 1.0);
    }
  }
  std::sort(t.begin(), t.end());
  return t;
}

}  // namespace

VoxelGrid thin_cell(const VoxelGrid& cell) {
  require_cube(cell, "thin_cell");
  const int n = cell.nx;
  const PeriodicCube cube(n);
  std::vector<std::uint8_t> solid(cell.size());
  for (std::size_t v = 0; v < cell.size(); ++v) solid[v] = cell.ids[v] != 0;
  static const int kDirections[6][3] = {{0, -1, 0}, {0, 1, 0}, {1, 0, 0}, {-1, 0, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<std::uint8_t> candidate(cell.size());
  std::vector<std::size_t> order;
  bool changed = true;
  while (changed) {
    changed = false;
    for (const auto& d : kDirections) {
      // Candidates are judged on the cell as the sub-iteration found it;
      // the flags are independent per voxel, so the parallel loop cannot
      // change the result. Small cells are not worth the threads.
#pragma omp parallel for schedule(static) if (n >= 48)
      for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
          for (int i = 0; i < n; ++i) {
            const std::size_t v = cube.index(i, j, k);
            candidate[v] = solid[v] && !solid[cube.neighbour(v, d[0], d[1], d[2])] && deletable(cube.gather(solid, v));
          }
      order.clear();
      for (std::size_t v = 0; v < cell.size(); ++v)
        if (candidate[v]) order.push_back(v);
      // Deleting one candidate can make the next one essential: re-check
      // each against the current cell before it goes.
      for (std::size_t v : order)
        if (deletable(cube.gather(solid, v))) solid[v] = 0, changed = true;
    }
  }
  VoxelGrid out(n, n, n, cell.voxel_size);
  out.origin = cell.origin;
  for (std::size_t v = 0; v < cell.size(); ++v) out.ids[v] = solid[v];
  return out;
}

int count_solid_components(const VoxelGrid& cell) { return count_pieces(cell, true, true, "count_solid_components"); }
int count_void_components(const VoxelGrid& cell) { return count_pieces(cell, false, false, "count_void_components"); }

SkeletonGraph skeleton_graph(const VoxelGrid& skeleton) {
  require_cube(skeleton, "skeleton_graph");
  const int n = skeleton.nx;
  const PeriodicCube cube(n);
  SkeletonGraph g;
  g.n = n;
  std::vector<int> vertex(skeleton.size(), -1);
  for (std::size_t v = 0; v < skeleton.size(); ++v) {
    if (!skeleton.ids[v]) continue;
    vertex[v] = static_cast<int>(g.voxel.size());
    g.voxel.push_back(static_cast<int>(v));
    g.position.push_back(Vec3(v % n + 0.5, v / n % n + 0.5, v / (std::size_t(n) * n) + 0.5) / double(n));
  }
  g.neighbours.resize(g.voxel.size());
  auto solid_at = [&](std::size_t v, int dx, int dy, int dz) {
    return skeleton.ids[cube.neighbour(v, dx, dy, dz)] != 0;
  };
  for (std::size_t u = 0; u < g.voxel.size(); ++u) {
    const std::size_t v = g.voxel[u];
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int len2 = dx * dx + dy * dy + dz * dz;
          if (len2 == 0 || !solid_at(v, dx, dy, dz)) continue;
          // Is there a voxel e away from u, with d - e a neighbour step,
          // nearer to both ends than they are to each other?
          bool shortcut = false;
          for (int ez = -1; ez <= 1 && !shortcut; ++ez)
            for (int ey = -1; ey <= 1 && !shortcut; ++ey)
              for (int ex = -1; ex <= 1 && !shortcut; ++ex) {
                const int fx = dx - ex, fy = dy - ey, fz = dz - ez;
                if (std::abs(fx) > 1 || std::abs(fy) > 1 || std::abs(fz) > 1) continue;
                const int e2 = ex * ex + ey * ey + ez * ez, f2 = fx * fx + fy * fy + fz * fz;
                if (e2 == 0 || f2 == 0 || e2 >= len2 || f2 >= len2) continue;
                shortcut = solid_at(v, ex, ey, ez);
              }
          if (!shortcut) g.neighbours[u].push_back(vertex[cube.neighbour(v, dx, dy, dz)]);
        }
    std::sort(g.neighbours[u].begin(), g.neighbours[u].end());
  }
  return g;
}

std::vector<SkeletonPath> skeleton_paths(const SkeletonGraph& graph) {
  std::vector<SkeletonPath> out;
  const Nodes nodes = find_nodes(graph, std::vector<std::uint8_t>(graph.voxel.size(), 0));
  for (auto& t : trace_paths(graph, nodes)) out.push_back(std::move(t.path));
  return out;
}

std::vector<int> simplify_polyline(const std::vector<Vec3>& points, double tolerance) {
  if (points.size() < 2)
    throw InputError("simplify_polyline: a polyline needs at least 2 points, got " + std::to_string(points.size()));
  if (!(tolerance >= 0))
    throw InputError("simplify_polyline: tolerance must be >= 0, got " + std::to_string(tolerance));
  std::vector<int> kept{0, static_cast<int>(points.size()) - 1};
  while (true) {
    double worst = -1;
    int at = -1;
    for (std::size_t s = 0; s + 1 < kept.size(); ++s)
      for (int i = kept[s] + 1; i < kept[s + 1]; ++i) {
        const double d = point_segment_distance(points[i], points[kept[s]], points[kept[s + 1]]);
        if (d > worst) worst = d, at = i;
      }
    if (at < 0 || worst <= tolerance) return kept;
    kept.insert(std::upper_bound(kept.begin(), kept.end(), at), at);
  }
}

std::vector<Segment> skeleton_segments(const VoxelGrid& cell, const SkeletonOptions& options) {
  if (!(options.tolerance >= 0))
    throw InputError("skeleton_segments: tolerance must be >= 0, got " + std::to_string(options.tolerance));
  VoxelGrid skeleton = thin_cell(cell);
  SkeletonGraph graph = skeleton_graph(skeleton);
  const std::vector<double> radius_of_vertex = inscribed_radius(cell, graph.voxel);
  std::vector<double> radius(cell.size(), 0.0);  // per voxel, kept when the graph is rebuilt
  for (std::size_t v = 0; v < graph.voxel.size(); ++v) radius[graph.voxel[v]] = radius_of_vertex[v];
  std::vector<std::uint8_t> joined(graph.voxel.size(), 0);
  Nodes nodes = find_nodes(graph, joined);
  std::vector<TracedPath> paths = trace_paths(graph, nodes);
  auto node_radius = [&](int id) {
    double r = 0;
    for (int v : nodes.members[id]) r = std::max(r, radius[graph.voxel[v]]);
    return r;
  };
  if (options.prune_spurs) {
    bool pruned = false;
    for (const auto& t : paths) {
      if (t.start < 0 || (nodes.kind[t.start] == 1) == (nodes.kind[t.end] == 1)) continue;
      const int junction = nodes.kind[t.start] == 2 ? t.start : t.end;
      if (polyline_length(t.path.points) > node_radius(junction)) continue;
      for (int v : t.vertices) skeleton.ids[graph.voxel[v]] = 0;
      pruned = true;
    }
    if (pruned) {
      graph = skeleton_graph(skeleton);
      joined.assign(graph.voxel.size(), 0);
      nodes = find_nodes(graph, joined);
      paths = trace_paths(graph, nodes);
    }
  }
  if (options.merge_junctions) {
    bool merged = false;
    for (const auto& t : paths) {
      if (t.start < 0 || nodes.kind[t.start] != 2 || nodes.kind[t.end] != 2) continue;
      if (polyline_length(t.path.points) > node_radius(t.start) + node_radius(t.end)) continue;
      for (int v : t.vertices) joined[v] = 1;
      merged = true;
    }
    if (merged) {
      nodes = find_nodes(graph, joined);
      paths = trace_paths(graph, nodes);
    }
  }
  std::vector<Segment> out;
  for (const auto& t : paths) {
    const auto& pts = t.path.points;
    const std::vector<int> kept = simplify_polyline(pts, options.tolerance);
    for (std::size_t s = 0; s + 1 < kept.size(); ++s) {
      const Segment seg{pts[kept[s]], pts[kept[s + 1]]};
      if ((seg.b - seg.a).norm() > 1e-12) out.push_back(seg);
    }
  }
  return out;
}

Segment cut_at_mirrors(const Segment& segment, double tolerance) {
  if (!(tolerance >= 0)) throw InputError("cut_at_mirrors: tolerance must be >= 0, got " + std::to_string(tolerance));
  Segment s = segment;
  while (true) {
    const double length = (s.b - s.a).norm();
    if (!(length > 2 * tolerance)) return s;
    // A piece shorter than the tolerance would be "covered" by any image
    // through the cut point, mirrored or not.
    auto try_cut = [&](double t, Segment& kept) {
      const Vec3 c = s.a + t * (s.b - s.a);
      const Segment first{s.a, c}, second{c, s.b};
      const bool keep_first = t >= 0.5;
      const Segment& cut = keep_first ? second : first;
      kept = keep_first ? first : second;
      return (cut.b - cut.a).norm() >= tolerance && covered(cut, {kept}, tolerance, true);
    };
    Segment best = s, kept;
    for (double t : mirror_crossings(s))
      if (try_cut(t, kept) && (kept.b - kept.a).norm() < (best.b - best.a).norm()) best = kept;
    // A centre of inversion or a two-fold axis lies at the midpoint of a
    // segment it maps onto itself; mirror planes are preferred, as the
    // exact place of the cut.
    if (best.a == s.a && best.b == s.b && try_cut(0.5, kept)) best = kept;
    if (best.a == s.a && best.b == s.b) return s;
    s = best;
  }
}

std::vector<Segment> fundamental_segments(const std::vector<Segment>& segments, double merge_tolerance) {
  if (!(merge_tolerance >= 0))
    throw InputError("fundamental_segments: merge_tolerance must be >= 0, got " + std::to_string(merge_tolerance));
  std::vector<Segment> images;
  for (const Segment& s : segments)
    if ((s.b - s.a).norm() > 1e-12) images.push_back(canonical_image(s));
  std::vector<int> order(images.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int p, int q) {
    return (images[p].b - images[p].a).norm() > (images[q].b - images[q].a).norm();
  });
  std::vector<Segment> kept;
  for (int i : order)
    if (!covered(images[i], kept, merge_tolerance)) kept.push_back(images[i]);
  return kept;
}

}  // namespace msfab
