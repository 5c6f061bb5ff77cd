#pragma once
// A closed triangle surface (an STL or OBJ part) painted into a voxel grid:
// a voxel takes the id when its centre lies inside the surface, as for the
// other shapes of voxel_shapes.hpp.
//
// Inside means a non-zero winding number. It is computed exactly along each
// column of voxel centres (a ray parallel to z): every triangle that the
// column pierces adds the sign of its normal's z component at the crossing,
// and a centre's winding number is the sum over the crossings above it. The
// pierce test is made watertight so that a column through a shared edge or
// vertex is counted by exactly one triangle of each sheet of the surface:
// edge functions are evaluated with the edge's endpoints in one canonical
// order (so the two triangles of an edge see exactly opposite values), and
// a zero value is resolved by the top-left rule of rasterization. With that,
// the result does not depend on how the surface is triangulated or oriented
// (inward-facing normals give -1 inside, which is still inside), and it is
// exact for meshes whose vertices sit on voxel-centre columns.
#include <array>
#include <string>
#include <vector>

#include "fem/voxel_grid.hpp"

namespace msfab {

struct TriangleSurface {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;  // indices into vertices
};

// Vertices with bit-identical coordinates merged into one (an STL file lists
// each triangle's corners separately); triangles keep their order.
TriangleSurface merge_equal_vertices(const TriangleSurface& surface);

// How far a surface is from bounding a volume. Every directed edge (a, b)
// of a triangle must be matched by a reverse edge (b, a) of another: then
// the surface is a closed, consistently oriented 2-cycle and the winding
// number is the same along any ray. Edges are compared by vertex index, so
// a surface read from STL needs merge_equal_vertices first.
struct SurfaceClosure {
  long long unmatched_edges = 0;            // directed edges without a reverse partner
  long long degenerate_triangles = 0;       // triangles with a repeated vertex (ignored)
  std::array<int, 2> example_edge{-1, -1};  // one unmatched edge, vertex indices
  bool closed() const { return unmatched_edges == 0; }
};
SurfaceClosure check_closure(const TriangleSurface& surface);

// Lower and upper corners of the vertices' bounding box.
std::array<Vec3, 2> bounding_box(const TriangleSurface& surface);

// One flag per voxel (grid order, x fastest): the voxel centre's winding
// number is non-zero. The surface must be closed (check_closure) for the
// result to mean inside; this function does not check it.
std::vector<char> voxels_inside(const VoxelGrid& grid, const TriangleSurface& surface);

// Paints `id` into the voxels whose centre lies inside; returns their count.
long long paint_surface(VoxelGrid& grid, const TriangleSurface& surface, int id);

}  // namespace msfab
