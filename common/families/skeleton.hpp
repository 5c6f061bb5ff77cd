#pragma once
// The topology of a microstructure as line segments (thesis §3.3.1,
// Fig. 3-5 b-c): a curve skeleton by 3-D thinning, the graph of its
// voxels, paths between junctions and ends, and each path simplified to a
// polyline within a tolerance.
//
// Cells are periodic cubes n x n x n (VoxelGrid, x fastest, any non-zero
// id solid). Positions are unit-cell coordinates: voxel (i, j, k) is
// centred at ((i + 1/2) / n, (j + 1/2) / n, (k + 1/2) / n).
#include <vector>

#include "core/types.hpp"
#include "fem/voxel_grid.hpp"

namespace msfab {

// Topology-preserving thinning after Lee, Kashyap & Chu (1994): 26-connected
// solid, 6-connected void, neighbourhoods wrapping around the cell. Each
// pass runs six sub-iterations, one per border direction (-y, +y, +x, -x,
// +z, -z); a sub-iteration collects, in scan order, the border voxels of
// its direction that are simple (Euler characteristic unchanged and the
// solid neighbours one 26-connected piece) and not end points (one solid
// neighbour), then deletes them one by one, re-checking each against the
// cell as it is at that moment. Passes repeat until nothing changes, so
// the result depends only on the input. Returns a 0/1 cell of the same
// size. InputError unless the cell is cubic with n >= 3 (smaller cells
// make a voxel its own neighbour).
VoxelGrid thin_cell(const VoxelGrid& cell);

// Pieces of solid under 26-adjacency (void under 6-adjacency), wrapping
// around the periodic cell.
int count_solid_components(const VoxelGrid& cell);
int count_void_components(const VoxelGrid& cell);

// The skeleton voxels as a graph. Edges join 26-neighbours, except that an
// edge is dropped when some common neighbour of its ends is nearer to both
// of them than they are to each other: the diagonals of a staircase and
// of a junction blob are not separate branches.
struct SkeletonGraph {
  int n = 0;
  std::vector<int> voxel;                    // vertex -> voxel index (x fastest)
  std::vector<Vec3> position;                // vertex -> voxel centre, unit-cell coordinates in [0, 1)
  std::vector<std::vector<int>> neighbours;  // sorted
};
// InputError unless the cell is cubic with n >= 3.
SkeletonGraph skeleton_graph(const VoxelGrid& skeleton);

// A chain of degree-2 vertices between two nodes, as unwrapped positions:
// consecutive points differ by the step between neighbouring voxels, so a
// path that wraps around the cell leaves [0, 1). Nodes are end vertices
// (degree 1) and junctions (degree >= 3); adjacent junction vertices form
// one node at their centroid. A closed loop without nodes starts and ends
// at its first vertex; its last point differs from the first by a lattice
// vector (zero unless the loop wraps around the cell).
struct SkeletonPath {
  std::vector<Vec3> points;
  bool closed = false;  // a loop without nodes
};
std::vector<SkeletonPath> skeleton_paths(const SkeletonGraph& graph);

// Indices of the points a polyline keeps: the two ends, then repeatedly
// the point farthest from the piece of the current polyline that spans it,
// until no point is farther than `tolerance`. Ascending. InputError for
// fewer than 2 points or a negative tolerance.
std::vector<int> simplify_polyline(const std::vector<Vec3>& points, double tolerance);

struct Segment {
  Vec3 a = Vec3::Zero(), b = Vec3::Zero();
};

// Thinning leaves two kinds of clutter where beams meet: spurs from bumps
// on the surface, and a junction spread over several nearby branch points
// joined by short links. Both are judged by the radius of the largest ball
// inside the solid at a junction (the distance from its voxels to the
// nearest void voxel): they lie within the junction's blob.
struct SkeletonOptions {
  double tolerance = 0.02;      // path simplification, unit-cell units (thesis: 0.02)
  bool prune_spurs = true;      // drop end branches no longer than their junction's radius
  bool merge_junctions = true;  // one node for junctions linked by a path no longer than their two radii
};

// Thinning, pruning and merging (one round each), graph, paths,
// simplification: every segment of the cell's skeleton. Zero-length pieces
// are dropped.
std::vector<Segment> skeleton_segments(const VoxelGrid& cell, const SkeletonOptions& options = {});

// The segments a template needs, given every segment of a cubic-symmetric
// cell's skeleton: each is replaced by its image, under the 48 symmetries
// of the cube (about the cell centre) and the lattice translations, whose
// midpoint lies in the fundamental domain 0 <= x <= y <= z <= 1/2; then,
// longest first, a segment is kept unless every point of it lies within
// `merge_tolerance` (unit-cell units) of an image of a segment kept
// before it. That drops the symmetric copies, and also the pieces of a
// beam that thinning, working in a fixed direction order, split
// differently in different copies of the slice. Segments are kept whole,
// not clipped to the domain: rasterizing a template re-applies the
// symmetries, so a whole beam reproduces its part of the structure with
// both ends free, where a clipped one would end at a mirror plane with a
// cap that is not there. InputError for a negative tolerance.
std::vector<Segment> fundamental_segments(const std::vector<Segment>& segments, double merge_tolerance = 0.05);

// A segment that runs through a mirror plane of the cell (or a centre of
// inversion, or a two-fold axis, at its midpoint) and is its own mirror
// image there is rebuilt by rasterization from the part on either side: the
// longer part, whose images cover the other within `tolerance` (unit-cell
// units), repeated while a cut removes at least `tolerance`. A whole edge of
// a cube frame becomes the half from a corner to the edge's midpoint, whose
// free end can then move off the edge where a whole beam could only tilt.
// InputError for a negative tolerance.
Segment cut_at_mirrors(const Segment& segment, double tolerance = 0.05);

}  // namespace msfab
