#include "gamut/structure_evolution.hpp"

#include <random>

#include "core/errors.hpp"
#include "gamut/structure_ops.hpp"

namespace msfab {

VoxelGrid evolve_structure(const VoxelGrid& cell, std::uint64_t seed, const BeamMoveOptions& o) {
  if (o.max_beams < 1 || !(o.min_radius > 0) || !(o.max_radius >= o.min_radius) || o.materials < 1 || o.cut_id < 0)
    throw InputError("beam move: need max_beams >= 1, 0 < min_radius <= max_radius, materials >= 1");
  VoxelGrid next = cell;
  std::mt19937_64 rng(seed);
  auto u01 = [&] { return double(rng() >> 11) * 0x1.0p-53; };
  const bool flat = cell.nz == 1;
  const int beams = 1 + static_cast<int>(rng() % o.max_beams);
  for (int b = 0; b < beams; ++b) {
    const Vec3 a(u01() * cell.nx, u01() * cell.ny, flat ? 0.5 : u01() * cell.nz);
    const Vec3 e(u01() * cell.nx, u01() * cell.ny, flat ? 0.5 : u01() * cell.nz);
    const double radius = o.min_radius + u01() * (o.max_radius - o.min_radius);
    const bool add = (rng() & 1) != 0;
    const int id = add ? 1 + static_cast<int>(rng() % o.materials) : o.cut_id;
    // Mirroring keeps only the fundamental domain, so every voxel the beam
    // touches passes its new value to its fundamental voxel: the beam then
    // appears with all its symmetric images.
    VoxelGrid painted = next;
    paint_beam(painted, a, e, radius, id);
    for (int k = 0; k < cell.nz; ++k)
      for (int j = 0; j < cell.ny; ++j)
        for (int i = 0; i < cell.nx; ++i)
          if (painted.at(i, j, k) != next.at(i, j, k)) {
            const auto f = fundamental_voxel(next, i, j, k, o.symmetry);
            painted.at(f[0], f[1], f[2]) = painted.at(i, j, k);
          }
    next = painted;
  }
  mirror_fundamental_domain(next, o.symmetry);
  clean_structure(next);
  return next;
}

}  // namespace msfab
