#pragma once
// Embedded-geometry helpers that paint material ids into a voxel grid. A
// voxel takes the id when its centre lies inside the shape; later paints
// overwrite earlier ones, so scenes are built like layers of paint.
#include <cstdint>

#include "fem/voxel_grid.hpp"

namespace msfab {

// Axis-aligned box [lo, hi] in physical coordinates.
void paint_box(VoxelGrid& grid, const Vec3& lo, const Vec3& hi, int id);

// Layers stacked along `axis` (0, 1, 2): starting at the grid origin, layer k
// has thickness thickness[k % n] and id ids[k % n], repeating to the end.
void paint_layers(VoxelGrid& grid, int axis, const std::vector<double>& thickness, const std::vector<int>& ids);

// Solid cylinder around the line through `center` along `axis`, radius r,
// limited to [from, to] along the axis.
void paint_cylinder(VoxelGrid& grid, int axis, const Vec3& center, double radius, double from, double to, int id);

// `count` helical fibres of radius `fiber_radius` winding around the line
// through `center` along `axis` at distance `helix_radius`, one turn per
// `pitch` length, evenly spaced in phase.
void paint_helical_fibers(VoxelGrid& grid, int axis, const Vec3& center, double helix_radius, double pitch,
                          double fiber_radius, int count, int id);

// 3D checkerboard of cubic cells of edge `cell`, counted from the grid
// origin: the voxel whose centre lies in cell (a, b, c) takes
// ids[(a + b + c) mod n]. Two ids give the classic checkerboard (a cell of
// one voxel alternates voxel by voxel); more ids give diagonal bands.
void paint_checker(VoxelGrid& grid, double cell, const std::vector<int>& ids);

// Every voxel takes an id drawn independently and uniformly from `ids`: the
// voxels are visited in storage order (x fastest, then y, then z) and voxel
// number m takes ids[r_m mod n], r_m being the m-th raw output of
// std::mt19937_64 seeded with `seed`. The standard fixes that engine's
// output sequence, so a seed gives the same field on every platform and
// compiler (no std::uniform_int_distribution, whose mapping is unspecified).
// The modulo bias is below n / 2^64.
void paint_random_field(VoxelGrid& grid, const std::vector<int>& ids, std::uint64_t seed);

}  // namespace msfab
