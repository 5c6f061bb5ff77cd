#pragma once
// Embedded-geometry helpers that paint material ids into a voxel grid. A
// voxel takes the id when its centre lies inside the shape; later paints
// overwrite earlier ones, so scenes are built like layers of paint.
#include "fem/voxel_grid.hpp"

namespace msfab {

// Axis-aligned box [lo, hi] in physical coordinates.
void paint_box(VoxelGrid& grid, const Vec3& lo, const Vec3& hi, int id);

// Layers stacked along `axis` (0, 1, 2): starting at the grid origin, layer k
// has thickness thickness[k % n] and id ids[k % n], repeating to the end.
void paint_layers(VoxelGrid& grid, int axis, const std::vector<double>& thickness,
                  const std::vector<int>& ids);

// Solid cylinder around the line through `center` along `axis`, radius r,
// limited to [from, to] along the axis.
void paint_cylinder(VoxelGrid& grid, int axis, const Vec3& center, double radius, double from,
                    double to, int id);

// `count` helical fibres of radius `fiber_radius` winding around the line
// through `center` along `axis` at distance `helix_radius`, one turn per
// `pitch` length, evenly spaced in phase.
void paint_helical_fibers(VoxelGrid& grid, int axis, const Vec3& center, double helix_radius,
                          double pitch, double fiber_radius, int count, int id);

}  // namespace msfab
