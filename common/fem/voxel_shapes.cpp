#include "fem/voxel_shapes.hpp"

#include <cmath>
#include <random>

#include "core/errors.hpp"

namespace msfab {
namespace {

template <class Inside>
void paint_where(VoxelGrid& grid, int id, Inside inside) {
  for (int k = 0; k < grid.nz; ++k)
    for (int j = 0; j < grid.ny; ++j)
      for (int i = 0; i < grid.nx; ++i)
        if (inside(grid.voxel_center(i, j, k))) grid.at(i, j, k) = id;
}

void check_axis(int axis) {
  if (axis < 0 || axis > 2) throw InputError("axis must be 0 (x), 1 (y) or 2 (z), got " + std::to_string(axis));
}

}  // namespace

void paint_box(VoxelGrid& grid, const Vec3& lo, const Vec3& hi, int id) {
  paint_where(grid, id,
              [&](const Vec3& p) { return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all(); });
}

void paint_layers(VoxelGrid& grid, int axis, const std::vector<double>& thickness, const std::vector<int>& ids) {
  check_axis(axis);
  if (thickness.empty() || thickness.size() != ids.size())
    throw InputError("layers need as many thicknesses as ids (and at least one)");
  double period = 0;
  for (double t : thickness) {
    if (!(t > 0)) throw InputError("layer thickness must be positive");
    period += t;
  }
  for (int k = 0; k < grid.nz; ++k)
    for (int j = 0; j < grid.ny; ++j)
      for (int i = 0; i < grid.nx; ++i) {
        const double s = std::fmod(grid.voxel_center(i, j, k)[axis] - grid.origin[axis], period);
        double acc = 0;
        for (size_t l = 0; l < thickness.size(); ++l) {
          acc += thickness[l];
          if (s < acc) {
            grid.at(i, j, k) = ids[l];
            break;
          }
        }
      }
}

void paint_cylinder(VoxelGrid& grid, int axis, const Vec3& center, double radius, double from, double to, int id) {
  check_axis(axis);
  paint_where(grid, id, [&](const Vec3& p) {
    Vec3 d = p - center;
    const double along = p[axis];
    d[axis] = 0;
    return d.norm() <= radius && along >= from && along <= to;
  });
}

void paint_helical_fibers(VoxelGrid& grid, int axis, const Vec3& center, double helix_radius, double pitch,
                          double fiber_radius, int count, int id) {
  check_axis(axis);
  if (!(pitch > 0) || count <= 0 || !(fiber_radius > 0))
    throw InputError("helical fibers need pitch > 0, count > 0 and fiber radius > 0");
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const double pi = std::acos(-1.0);
  // Distance to a helix has no closed form; minimize over the curve
  // parameter on a fine sampling of one turn around the voxel's height.
  const int samples = 64;
  paint_where(grid, id, [&](const Vec3& p) {
    for (int f = 0; f < count; ++f) {
      const double phase = 2 * pi * f / count;
      for (int s = -samples / 2; s <= samples / 2; ++s) {
        const double z = p[axis] + pitch * s / samples;
        const double theta = 2 * pi * (z - center[axis]) / pitch + phase;
        Vec3 c;
        c[axis] = z;
        c[u] = center[u] + helix_radius * std::cos(theta);
        c[v] = center[v] + helix_radius * std::sin(theta);
        if ((p - c).squaredNorm() <= fiber_radius * fiber_radius) return true;
      }
    }
    return false;
  });
}

void paint_checker(VoxelGrid& grid, double cell, const std::vector<int>& ids) {
  if (!(cell > 0) || !std::isfinite(cell)) throw InputError("checker cell size must be positive and finite");
  if (ids.empty()) throw InputError("a checkerboard needs at least one id");
  const long n = static_cast<long>(ids.size());
  for (int k = 0; k < grid.nz; ++k)
    for (int j = 0; j < grid.ny; ++j)
      for (int i = 0; i < grid.nx; ++i) {
        const Vec3 s = (grid.voxel_center(i, j, k) - grid.origin) / cell;
        const long parity = static_cast<long>(std::floor(s[0])) + static_cast<long>(std::floor(s[1])) +
                            static_cast<long>(std::floor(s[2]));
        grid.at(i, j, k) = ids[((parity % n) + n) % n];
      }
}

void paint_random_field(VoxelGrid& grid, const std::vector<int>& ids, std::uint64_t seed) {
  if (ids.empty()) throw InputError("a random field needs at least one id");
  std::mt19937_64 rng(seed);
  const std::uint64_t n = ids.size();
  for (int& id : grid.ids) id = ids[rng() % n];  // storage order: x fastest
}

}  // namespace msfab
