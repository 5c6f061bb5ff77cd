#include "families/beam_template.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/errors.hpp"

namespace msfab {
namespace {

constexpr double kShortestBeam = 1e-10;
constexpr double kPi = 3.14159265358979323846;
constexpr double kParallelWork = 1e6;  // inner-loop evaluations worth a parallel region
// Six logistic scales out the kernel's tail is below 1e-2.6 of a voxel;
// the occupancy ignores material 4 pi scales (two voxels unsharpened) away.
constexpr double kKernelReach = 4 * kPi;

// A beam moved to one of its images: its end, frame and reach.
struct PlacedBeam {
  Vec3 a, x, y, z;
  double length, r0, r1, cap;
  bool caps;
  Vec3 lo, hi;  // box around the beam, padded by its reach and a margin
  bool near(const Vec3& p) const { return !((p.array() < lo.array()).any() || (p.array() > hi.array()).any()); }
};

double cap_radius(double r0, double r1) { return std::min(r0 + 0.05 * r1, 0.05 * r0 + r1); }

double placed_distance(const PlacedBeam& P, const Vec3& p) {
  const Vec3 d = p - P.a;
  const double u = d.dot(P.x), v = d.dot(P.y), w = d.dot(P.z);
  const double qu = std::abs(u - 0.5 * P.length) - 0.5 * P.length;
  const double qv = std::abs(v) - P.r0, qw = std::abs(w) - P.r1;
  const double ou = std::max(qu, 0.0), ov = std::max(qv, 0.0), ow = std::max(qw, 0.0);
  double dist = std::sqrt(ou * ou + ov * ov + ow * ow) + std::min(std::max({qu, qv, qw}), 0.0);
  if (P.caps) {
    const double prism = std::sqrt(ov * ov + ow * ow) + std::min(std::max(qv, qw), 0.0);
    const double side = v * v + w * w;
    const double to_a = std::sqrt(u * u + side) - P.cap;
    const double to_b = std::sqrt((u - P.length) * (u - P.length) + side) - P.cap;
    dist = std::min({dist, std::max(to_a, prism), std::max(to_b, prism)});
  }
  return dist;
}

// Past 37 scales exp(-x) is below half an ulp of 1, so the logistic is
// exactly 1 and exp, where the fit spends much of its time, need not run.
double logistic(double x) { return x > 37.0 ? 1.0 : 1.0 / (1.0 + std::exp(-x)); }

// A logistic-smoothed interval [-lo, hi] at t: the difference of two
// logistic distribution functions of the given sharpness (1 / scale).
double smoothed_interval(double t, double lo, double hi, double sharpness) {
  const double inside = logistic((hi - t) * sharpness) + logistic((t + lo) * sharpness) - 1.0;
  return std::max(inside, 0.0);
}

double placed_occupancy(const PlacedBeam& P, const Vec3& p, double sharpness) {
  const Vec3 d = p - P.a;
  // Beyond the kernel's reach across the section the occupancy counts as
  // none, as it does for images that far away, and exp need not run.
  const double reach = kKernelReach / sharpness;
  const double v = d.dot(P.y);
  if (std::abs(v) > P.r0 + reach) return 0.0;
  const double w = d.dot(P.z);
  if (std::abs(w) > P.r1 + reach) return 0.0;
  const double across = smoothed_interval(v, P.r0, P.r0, sharpness) * smoothed_interval(w, P.r1, P.r1, sharpness);
  if (across < 1e-12) return 0.0;
  // A dome reaches sqrt(cap^2 - rho^2) past the end at section radius rho.
  const double rho2 = v * v + w * w;
  const double dome = P.caps && rho2 < P.cap * P.cap ? std::sqrt(P.cap * P.cap - rho2) : 0.0;
  return across * smoothed_interval(d.dot(P.x), dome, P.length + dome, sharpness);
}

Vec3 centre(const FundamentalVoxels& fv, int v) {
  const auto& ijk = fv.voxel[v];
  const double n = fv.n;
  return Vec3((ijk[0] + 0.5) / n, (ijk[1] + 0.5) / n, (ijk[2] + 0.5) / n);
}

PlacedBeam place(const Beam& beam, const BeamFrame& f, bool caps) {
  PlacedBeam P;
  P.a = beam.a;
  P.x = f.x, P.y = f.y, P.z = f.z;
  P.length = f.length;
  P.r0 = beam.r0, P.r1 = beam.r1, P.cap = cap_radius(beam.r0, beam.r1);
  P.caps = caps;
  return P;
}

// The beam's images under the cube symmetries and lattice translations
// that come within `margin` of [0, 1/2]^3, where the fundamental voxel
// centres lie. Each image carries the image of the frame, not a frame
// recomputed from its axis, so it is the same cuboid moved.
std::vector<PlacedBeam> images_near_domain(const Beam& beam, bool caps, double margin) {
  std::vector<PlacedBeam> images;
  const BeamFrame f = beam_frame(beam);
  if (f.length < kShortestBeam) return images;
  const double reach = std::hypot(beam.r0, beam.r1) + margin;
  for (const Mat3& S : cell_symmetries()) {
    Beam image = beam;
    image.a = apply_cell_symmetry(S, beam.a);
    image.b = apply_cell_symmetry(S, beam.b);
    BeamFrame g = f;
    g.x = S * f.x, g.y = S * f.y, g.z = S * f.z;
    const Vec3 lo = image.a.cwiseMin(image.b).array() - reach, hi = image.a.cwiseMax(image.b).array() + reach;
    int first[3], last[3];
    for (int i = 0; i < 3; ++i) first[i] = int(std::ceil(-hi[i])), last[i] = int(std::floor(0.5 - lo[i]));
    for (int lz = first[2]; lz <= last[2]; ++lz)
      for (int ly = first[1]; ly <= last[1]; ++ly)
        for (int lx = first[0]; lx <= last[0]; ++lx) {
          const Vec3 shift(lx, ly, lz);
          Beam moved = image;
          moved.a += shift;
          PlacedBeam P = place(moved, g, caps);
          P.lo = lo + shift, P.hi = hi + shift;
          images.push_back(P);
        }
  }
  return images;
}

// `where` names the caller and the beam, ending in ": ".
void check_beam(const Beam& b, const std::string& where) {
  if (!b.a.allFinite() || !b.b.allFinite()) throw InputError(where + "end points must be finite");
  if (!(b.r0 >= 0) || !std::isfinite(b.r0))
    throw InputError(where + "r0 must be finite and >= 0, got " + std::to_string(b.r0));
  if (!(b.r1 >= 0) || !std::isfinite(b.r1))
    throw InputError(where + "r1 must be finite and >= 0, got " + std::to_string(b.r1));
  if (!std::isfinite(b.theta)) throw InputError(where + "theta must be finite");
}

void check_template(const BeamTemplate& tpl, int n, const char* what) {
  if (n < 1) throw InputError(std::string(what) + ": resolution must be at least 1, got " + std::to_string(n));
  check_template(tpl, what);
}

// Smallest signed distance over all beams at each fundamental voxel.
std::vector<double> template_distance(const BeamTemplate& tpl, const FundamentalVoxels& fv, double cutoff) {
  std::vector<double> dist(fv.voxel.size(), cutoff);
  for (const Beam& b : tpl.beams) {
    const std::vector<double> d = beam_distance(b, tpl.caps, fv, cutoff);
    for (std::size_t i = 0; i < dist.size(); ++i) dist[i] = std::min(dist[i], d[i]);
  }
  return dist;
}

}  // namespace

void check_template(const BeamTemplate& tpl, const std::string& context) {
  for (std::size_t i = 0; i < tpl.beams.size(); ++i)
    check_beam(tpl.beams[i], context + ": beam " + std::to_string(i) + ": ");
}

BeamFrame beam_frame(const Beam& beam) {
  BeamFrame f;
  const Vec3 axis = beam.b - beam.a;
  f.length = axis.norm();
  if (f.length < kShortestBeam) return f;
  f.x = axis / f.length;
  const Vec3 up = std::abs(f.x.y()) > 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  f.z = f.x.cross(up).normalized();
  f.y = f.z.cross(f.x);
  // Turning about x: x cross y = z and x cross z = -y.
  const double c = std::cos(beam.theta), s = std::sin(beam.theta);
  const Vec3 y = c * f.y + s * f.z, z = c * f.z - s * f.y;
  f.y = y, f.z = z;
  return f;
}

double beam_signed_distance(const Beam& beam, bool caps, const Vec3& p) {
  const BeamFrame f = beam_frame(beam);
  if (f.length < kShortestBeam) return std::numeric_limits<double>::infinity();
  return placed_distance(place(beam, f, caps), p);
}

std::vector<double> beam_distance(const Beam& beam, bool caps, const FundamentalVoxels& fv, double cutoff) {
  if (!(cutoff > 0)) throw InputError("beam_distance: cutoff must be > 0, got " + std::to_string(cutoff));
  check_beam(beam, "beam_distance: ");
  std::vector<double> dist(fv.voxel.size(), cutoff);
  const std::vector<PlacedBeam> images = images_near_domain(beam, caps, cutoff);
  const int count = static_cast<int>(fv.voxel.size());
  // Threads pay off only on fine cells; the fit calls this thousands of times.
  const bool parallel = double(count) * images.size() > kParallelWork;
#pragma omp parallel for schedule(static) if (parallel)
  for (int v = 0; v < count; ++v) {
    const Vec3 p = centre(fv, v);
    double best = cutoff;
    for (const PlacedBeam& P : images)
      if (P.near(p)) best = std::min(best, placed_distance(P, p));
    dist[v] = best;
  }
  return dist;
}

std::vector<double> beam_occupancy(const Beam& beam, bool caps, const FundamentalVoxels& fv, double sharpening) {
  check_beam(beam, "beam_occupancy: ");
  if (!(sharpening >= 1) || !std::isfinite(sharpening))
    throw InputError("beam_occupancy: sharpening must be >= 1, got " + std::to_string(sharpening));
  std::vector<double> occ(fv.voxel.size(), 0.0);
  const double sharpness = 2 * kPi * fv.n * sharpening;
  const std::vector<PlacedBeam> images = images_near_domain(beam, caps, kKernelReach / sharpness);
  const int count = static_cast<int>(fv.voxel.size());
  const bool parallel = double(count) * images.size() > kParallelWork;
#pragma omp parallel for schedule(static) if (parallel)
  for (int v = 0; v < count; ++v) {
    const Vec3 p = centre(fv, v);
    double best = 0;
    for (const PlacedBeam& P : images)
      if (P.near(p)) best = std::max(best, placed_occupancy(P, p, sharpness));
    occ[v] = best;
  }
  return occ;
}

std::vector<double> periodic_blur(const std::vector<double>& field, int n, double width) {
  if (n < 1 || field.size() != std::size_t(n) * n * n)
    throw InputError("periodic_blur: field has " + std::to_string(field.size()) + " values for a cell of " +
                     std::to_string(n) + "^3");
  if (!(width > 0) || !std::isfinite(width))
    throw InputError("periodic_blur: width must be > 0 voxels, got " + std::to_string(width));
  const int reach = static_cast<int>(std::ceil(3 * width));
  std::vector<double> kernel(2 * reach + 1);
  double total = 0;
  for (int k = -reach; k <= reach; ++k) total += kernel[k + reach] = std::exp(-0.5 * k * k / (width * width));
  for (double& w : kernel) w /= total;
  // Each line of the cell along the axis is copied with its periodic
  // continuation on both sides, so the inner loop reads contiguous values
  // and does no index arithmetic; the sum runs in kernel order as before.
  const int padded = n + 2 * reach;
  std::vector<int> wrapped(padded);
  for (int q = 0; q < padded; ++q) wrapped[q] = ((q - reach) % n + n) % n;
  std::vector<double> a = field, b(field.size());
  const int lines = n * n;
  const bool parallel = double(lines) * n * kernel.size() > kParallelWork;
  for (int axis = 0; axis < 3; ++axis) {
    const int stride = axis == 0 ? 1 : axis == 1 ? n : n * n;
#pragma omp parallel if (parallel)
    {
      std::vector<double> line(padded);
#pragma omp for schedule(static)
      for (int l = 0; l < lines; ++l) {
        // The line's first voxel: lines are indexed by the two other coordinates.
        const int base = axis == 0 ? l * n : axis == 1 ? l % n + l / n * n * n : l;
        for (int q = 0; q < padded; ++q) line[q] = a[base + wrapped[q] * stride];
        for (int c = 0; c < n; ++c) {
          double sum = 0;
          for (int k = 0; k <= 2 * reach; ++k) sum += kernel[k] * line[c + k];
          b[base + c * stride] = sum;
        }
      }
    }
    std::swap(a, b);
  }
  return a;
}

VoxelGrid rasterize_template(const BeamTemplate& tpl, int n) {
  check_template(tpl, n, "rasterize_template");
  const FundamentalVoxels fv = fundamental_voxels(n);
  const std::vector<double> dist = template_distance(tpl, fv, 0.5 / n);
  VoxelGrid cell(n, n, n, 1.0 / n);
  for (std::size_t v = 0; v < cell.size(); ++v) cell.ids[v] = dist[fv.orbit_of[v]] <= 0 ? 1 : 0;
  return cell;
}

std::vector<double> rasterize_template_smooth(const BeamTemplate& tpl, int n, double width, double sharpening) {
  check_template(tpl, n, "rasterize_template_smooth");
  const FundamentalVoxels fv = fundamental_voxels(n);
  std::vector<double> best(fv.voxel.size(), 0.0);
  for (const Beam& b : tpl.beams) {
    const std::vector<double> occ = beam_occupancy(b, tpl.caps, fv, sharpening);
    for (std::size_t i = 0; i < best.size(); ++i) best[i] = std::max(best[i], occ[i]);
  }
  std::vector<double> occ(std::size_t(n) * n * n);
  for (std::size_t v = 0; v < occ.size(); ++v) occ[v] = best[fv.orbit_of[v]];
  return periodic_blur(occ, n, width);
}

VecX template_parameters(const BeamTemplate& tpl) {
  VecX x(kBeamParameters * static_cast<int>(tpl.beams.size()));
  for (std::size_t i = 0; i < tpl.beams.size(); ++i) {
    const Beam& b = tpl.beams[i];
    x.segment<kBeamParameters>(kBeamParameters * i) << b.a, b.b, b.r0, b.r1, b.theta;
  }
  return x;
}

BeamTemplate template_from_parameters(const VecX& x, bool caps) {
  if (x.size() % kBeamParameters != 0)
    throw InputError("template_from_parameters: " + std::to_string(x.size()) +
                     " parameters is not a whole number of beams (9 each)");
  BeamTemplate tpl;
  tpl.caps = caps;
  for (int i = 0; i < x.size() / kBeamParameters; ++i) {
    const auto p = x.segment<kBeamParameters>(kBeamParameters * i);
    Beam b;
    b.a = p.segment<3>(0);
    b.b = p.segment<3>(3);
    b.r0 = p[6], b.r1 = p[7], b.theta = p[8];
    tpl.beams.push_back(b);
  }
  return tpl;
}

}  // namespace msfab
