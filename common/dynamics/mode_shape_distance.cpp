#include "dynamics/mode_shape_distance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/errors.hpp"
#include "fem/hex_boundary.hpp"

namespace msfab {

namespace {

struct Triangle {
  Vec3 a, b, c;
};

// Closest point of triangle abc to p, by the Voronoi region of p (vertex,
// edge or face), after Ericson, Real-Time Collision Detection §5.1.5.
Vec3 closest_point(const Vec3& p, const Triangle& t) {
  const Vec3 ab = t.b - t.a, ac = t.c - t.a, ap = p - t.a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return t.a;
  const Vec3 bp = p - t.b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return t.b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return t.a + (d1 / (d1 - d3)) * ab;
  const Vec3 cp = p - t.c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return t.c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return t.a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return t.b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (t.c - t.b);
  const double sum = va + vb + vc;
  if (!(sum > 0)) return t.a;  // degenerate (zero-area) triangle
  return t.a + (vb / sum) * ab + (vc / sum) * ac;
}

// Triangles binned into a uniform grid of cubic cells; each triangle is
// listed in every cell its bounding box touches.
class TriangleGrid {
 public:
  explicit TriangleGrid(const std::vector<Triangle>& triangles) : triangles_(triangles) {
    lo_ = Vec3::Constant(std::numeric_limits<double>::infinity());
    Vec3 hi = -lo_;
    double mean_size = 0;
    for (const Triangle& t : triangles_) {
      const Vec3 tlo = t.a.cwiseMin(t.b).cwiseMin(t.c), thi = t.a.cwiseMax(t.b).cwiseMax(t.c);
      boxes_lo_.push_back(tlo);
      boxes_hi_.push_back(thi);
      lo_ = lo_.cwiseMin(tlo);
      hi = hi.cwiseMax(thi);
      mean_size += (thi - tlo).maxCoeff();
    }
    mean_size /= static_cast<double>(triangles_.size());
    const Vec3 extent = hi - lo_;
    h_ = std::max(mean_size, 1e-9 * std::max(extent.maxCoeff(), 1e-300));
    // A surface fills few cells of its box; cap the cell count so memory
    // stays proportional to the number of triangles.
    const double cap = 8.0 * static_cast<double>(triangles_.size()) + 64.0;
    for (;;) {
      for (int a = 0; a < 3; ++a) n_[a] = std::max(1, static_cast<int>(std::ceil(extent[a] / h_)));
      const double cells = double(n_[0]) * n_[1] * n_[2];
      if (cells <= cap) break;
      h_ *= std::cbrt(cells / cap) * 1.01;
    }
    const size_t cells = size_t(n_[0]) * n_[1] * n_[2];
    start_.assign(cells + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<int> fill;
      if (pass == 1) {
        for (size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
        entries_.resize(static_cast<size_t>(start_[cells]));
        fill.assign(start_.begin(), start_.end() - 1);
      }
      for (int t = 0; t < static_cast<int>(triangles_.size()); ++t) {
        const auto from = cell_of(boxes_lo_[static_cast<size_t>(t)]);
        const auto to = cell_of(boxes_hi_[static_cast<size_t>(t)]);
        for (int k = from[2]; k <= to[2]; ++k)
          for (int j = from[1]; j <= to[1]; ++j)
            for (int i = from[0]; i <= to[0]; ++i) {
              const size_t c = index(i, j, k);
              if (pass == 0)
                ++start_[c + 1];
              else
                entries_[static_cast<size_t>(fill[c]++)] = t;
            }
      }
    }
  }

  // Distance from p to the nearest triangle: cells are visited in rings of
  // growing Chebyshev radius r around p's cell. The cells not yet visited
  // lie outside the box of rings 0..r, so the search stops once the best
  // distance is no larger than p's distance to that box's open sides (sides
  // at the grid's edge have no cells beyond them). It also stops as soon as
  // a triangle within good_enough is found; the value returned is then an
  // upper bound <= good_enough rather than the distance.
  double distance(const Vec3& p, double good_enough) const {
    const double enough2 = good_enough * good_enough;
    std::array<long, 3> c;
    Vec3 local;
    for (int a = 0; a < 3; ++a) {
      local[a] = (p[a] - lo_[a]) / h_;
      c[a] = static_cast<long>(std::max(-1e9, std::min(1e9, std::floor(local[a]))));
    }
    long r0 = 0, r_max = 0;
    for (int a = 0; a < 3; ++a) {
      r0 = std::max({r0, -c[a], c[a] - (n_[a] - 1)});
      r_max = std::max({r_max, c[a], (n_[a] - 1) - c[a]});
    }
    double best2 = std::numeric_limits<double>::infinity();
    for (long r = r0; r <= r_max; ++r) {
      const long ilo = std::max(0L, c[0] - r), ihi = std::min<long>(n_[0] - 1, c[0] + r);
      const long jlo = std::max(0L, c[1] - r), jhi = std::min<long>(n_[1] - 1, c[1] + r);
      const long klo = std::max(0L, c[2] - r), khi = std::min<long>(n_[2] - 1, c[2] + r);
      for (long k = klo; k <= khi; ++k)
        for (long j = jlo; j <= jhi; ++j)
          for (long i = ilo; i <= ihi; ++i) {
            const long ring = std::max({std::abs(i - c[0]), std::abs(j - c[1]), std::abs(k - c[2])});
            if (ring != r) continue;
            const size_t cell = index(int(i), int(j), int(k));
            for (int e = start_[cell]; e < start_[cell + 1]; ++e) {
              const int id = entries_[static_cast<size_t>(e)];
              // The triangle's box bounds its distance from below.
              const Vec3 gap = (boxes_lo_[static_cast<size_t>(id)] - p)
                                   .cwiseMax(p - boxes_hi_[static_cast<size_t>(id)])
                                   .cwiseMax(0.0);
              if (gap.squaredNorm() >= best2) continue;
              const Triangle& t = triangles_[static_cast<size_t>(id)];
              best2 = std::min(best2, (closest_point(p, t) - p).squaredNorm());
              if (best2 <= enough2) return std::sqrt(best2);
            }
          }
      double reach = std::numeric_limits<double>::infinity();
      for (int a = 0; a < 3; ++a) {
        if (c[a] - r > 0) reach = std::min(reach, local[a] - double(c[a] - r));
        if (c[a] + r < n_[a] - 1) reach = std::min(reach, double(c[a] + r + 1) - local[a]);
      }
      reach *= h_;
      if (best2 <= reach * reach) break;
    }
    return std::sqrt(best2);
  }

 private:
  std::array<int, 3> cell_of(const Vec3& p) const {
    std::array<int, 3> c;
    for (int a = 0; a < 3; ++a)
      c[a] = std::min(n_[a] - 1, std::max(0, static_cast<int>(std::floor((p[a] - lo_[a]) / h_))));
    return c;
  }
  size_t index(int i, int j, int k) const { return size_t(i) + size_t(n_[0]) * (size_t(j) + size_t(n_[1]) * k); }

  const std::vector<Triangle>& triangles_;
  Vec3 lo_;
  double h_ = 1.0;
  std::array<int, 3> n_{{1, 1, 1}};
  std::vector<int> start_, entries_;
  std::vector<Vec3> boxes_lo_, boxes_hi_;  // per triangle
};

std::vector<Triangle> deformed_triangles(const ModeShapeSurface& s, const VecX& u) {
  if (u.size() != 3 * s.rest.rows())
    throw InputError("mode shape distance: displacement has " + std::to_string(u.size()) + " entries for " +
                     std::to_string(s.rest.rows()) + " nodes");
  auto position = [&](int n) -> Vec3 { return s.rest.row(n).transpose() + u.segment<3>(3 * n); };
  std::vector<Triangle> tris;
  tris.reserve(4 * s.faces.size());
  for (const auto& f : s.faces) {
    const Vec3 p[4] = {position(f[0]), position(f[1]), position(f[2]), position(f[3])};
    const Vec3 centre = 0.25 * (p[0] + p[1] + p[2] + p[3]);
    for (int e = 0; e < 4; ++e) tris.push_back({p[e], p[(e + 1) % 4], centre});
  }
  return tris;
}

// Lattice points of every triangle. Neighbouring triangles compute their
// shared points from the same vertices with the same (commutative) sums, so
// duplicates are bitwise equal and are removed.
std::vector<Vec3> sample_points(const std::vector<Triangle>& tris, int order) {
  std::vector<std::array<double, 3>> pts;
  pts.reserve(tris.size() * size_t(order + 1) * size_t(order + 2) / 2);
  for (const Triangle& t : tris)
    for (int i = 0; i <= order; ++i)
      for (int j = 0; i + j <= order; ++j) {
        const int k = order - i - j;
        const Vec3 p = (double(i) * t.a + double(j) * t.b + double(k) * t.c) / double(order);
        pts.push_back({p.x(), p.y(), p.z()});
      }
  std::sort(pts.begin(), pts.end());
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  std::vector<Vec3> out(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) out[i] = Vec3(pts[i][0], pts[i][1], pts[i][2]);
  return out;
}

// max over samples of the distance to the grid's triangles, exact when it
// is <= upper and +inf otherwise. A sample that is no farther than the
// running maximum cannot raise it, so its search stops at the first triangle
// that close (Taha & Hanbury's early break); every sample that raises the
// maximum is searched fully, so the maximum is exact and independent of the
// thread count. Starting the running maximum at `lower` (a value known not
// to exceed the caller's final answer) only skips work.
double directed_distance(const std::vector<Vec3>& from, const TriangleGrid& to, double lower, double upper) {
  double worst = 0.0;
  int exceeded = 0;
  const long n = static_cast<long>(from.size());
// Small sets are not worth a parallel region.
#pragma omp parallel reduction(max : worst) if (n > 4096)
  {
    double running = lower;
#pragma omp for schedule(static)
    for (long i = 0; i < n; ++i) {
      int stop;
#pragma omp atomic read relaxed
      stop = exceeded;
      if (stop) continue;
      const double d = to.distance(from[static_cast<size_t>(i)], running);
      if (d > upper) {
#pragma omp atomic write relaxed
        exceeded = 1;
      }
      running = std::max(running, d);
      worst = std::max(worst, d);
    }
  }
  return exceeded ? std::numeric_limits<double>::infinity() : std::max(worst, lower);
}

double max_nodal_displacement(const VecX& u) {
  double m = 0;
  for (Eigen::Index n = 0; n + 2 < u.size(); n += 3) m = std::max(m, u.segment<3>(n).norm());
  return m;
}

}  // namespace

ModeShapeSurface mode_shape_surface(const HexMesh& mesh) {
  ModeShapeSurface s;
  s.rest = mesh.nodes;
  if (mesh.num_elements() == 0) throw InputError("boundary surface: the mesh has no elements");
  s.diagonal = (mesh.bbox_max() - mesh.bbox_min()).norm();

  s.faces = hex_boundary(mesh).faces;
  return s;
}

double hausdorff_distance(const ModeShapeSurface& a, const VecX& ua, const ModeShapeSurface& b, const VecX& ub,
                          int samples, double upper_bound) {
  if (samples < 1) throw InputError("hausdorff distance: samples must be at least 1");
  if (a.faces.empty() || b.faces.empty()) throw InputError("hausdorff distance: a surface has no faces");
  const std::vector<Triangle> ta = deformed_triangles(a, ua), tb = deformed_triangles(b, ub);
  const TriangleGrid grid_a(ta), grid_b(tb);
  const double ab = directed_distance(sample_points(ta, samples), grid_b, 0.0, upper_bound);
  if (!(ab <= upper_bound)) return std::numeric_limits<double>::infinity();
  return directed_distance(sample_points(tb, samples), grid_a, ab, upper_bound);
}

namespace {

// mode_shape_distance, exact when <= upper (relative) and +inf otherwise.
double bounded_mode_distance(const ModeShapeSurface& ref, const VecX& ref_mode, const ModeShapeSurface& other,
                             const VecX& other_mode, const ModeDistanceOptions& options, double upper) {
  if (!(options.amplitude_fraction > 0) || !std::isfinite(options.amplitude_fraction))
    throw InputError("mode shape distance: amplitude_fraction must be positive");
  const double target = options.amplitude_fraction * ref.diagonal;
  const double mr = max_nodal_displacement(ref_mode), mo = max_nodal_displacement(other_mode);
  if (!(mr > 0) || !(mo > 0)) throw InputError("mode shape distance: a mode is zero");
  const VecX ur = (target / mr) * ref_mode;
  const VecX uo = (target / mo) * other_mode;
  const double bound = upper * ref.diagonal;
  const double plus = hausdorff_distance(ref, ur, other, uo, options.samples, bound);
  const double minus = hausdorff_distance(ref, ur, other, -uo, options.samples, std::min(plus, bound));
  return std::min(plus, minus) / ref.diagonal;
}

}  // namespace

double mode_shape_distance(const ModeShapeSurface& ref, const VecX& ref_mode, const ModeShapeSurface& other,
                           const VecX& other_mode, const ModeDistanceOptions& options) {
  return bounded_mode_distance(ref, ref_mode, other, other_mode, options, std::numeric_limits<double>::infinity());
}

std::vector<ModeMatch> match_modes(const ModeShapeSurface& ref, const MatX& ref_modes, const ModeShapeSurface& other,
                                   const MatX& other_modes, int window, const ModeDistanceOptions& options) {
  if (window < 0) throw InputError("mode matching: window must be >= 0");
  std::vector<ModeMatch> matches(static_cast<size_t>(other_modes.cols()));
  for (Eigen::Index i = 0; i < other_modes.cols(); ++i) {
    ModeMatch& m = matches[static_cast<size_t>(i)];
    m.distance = std::numeric_limits<double>::infinity();
    const Eigen::Index lo = std::max<Eigen::Index>(0, i - window);
    const Eigen::Index hi = std::min<Eigen::Index>(ref_modes.cols() - 1, i + window);
    for (Eigen::Index j = lo; j <= hi; ++j) {
      const double d = bounded_mode_distance(ref, ref_modes.col(j), other, other_modes.col(i), options, m.distance);
      if (d < m.distance) {
        m.distance = d;
        m.reference_mode = static_cast<int>(j);
      }
    }
    if (m.reference_mode < 0)
      throw InputError("mode matching: no reference mode within the window of mode " + std::to_string(i));
  }
  return matches;
}

}  // namespace msfab
