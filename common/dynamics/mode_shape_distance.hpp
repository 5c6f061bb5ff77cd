#pragma once
// Geometric difference between deformation modes of two meshes of one
// shape (thesis §4.3.1): each mesh's boundary surface is displaced by its
// mode at a fixed amplitude and the two deformed surfaces are compared by
// the symmetric Hausdorff distance, relative to the bounding-box diagonal.
// Dynamics-aware coarsening accepts a coarse mesh when its first modes are
// within 5% of the convergent mesh's.
#include <array>
#include <limits>
#include <vector>

#include "core/types.hpp"
#include "fem/hex_mesh.hpp"

namespace msfab {

// The boundary of a hex mesh as the mode-shape distance samples it: the
// element faces not shared by two elements.
// Each quad is split into four triangles around its centre, so the surface
// displaced by a nodal field is piecewise linear and exactly reproducible.
struct ModeShapeSurface {
  NodeArray rest;                         // rest positions of every mesh node
  std::vector<std::array<int, 4>> faces;  // boundary quads, corners in cyclic order
  double diagonal = 0.0;                  // bounding-box diagonal of the rest mesh
};
ModeShapeSurface mode_shape_surface(const HexMesh& mesh);

// Symmetric Hausdorff distance (metres) between surface a displaced by ua
// and surface b displaced by ub (DOF vectors, node-major 3 n + c). Each
// surface is sampled at the points of a barycentric lattice of order
// `samples` on every triangle (vertices and edge points included), and the
// distance from each sample to the other surface's triangles is exact; a
// uniform grid of triangles keeps the search near-linear. Samples are
// evaluated in parallel; the maximum does not depend on the thread count.
// With a finite upper_bound the result is exact when it is <= upper_bound
// and +inf otherwise, which lets comparisons against a best-so-far stop
// early.
double hausdorff_distance(const ModeShapeSurface& a, const VecX& ua, const ModeShapeSurface& b, const VecX& ub,
                          int samples = 2, double upper_bound = std::numeric_limits<double>::infinity());

struct ModeDistanceOptions {
  // Each mode is scaled so that its largest nodal displacement is this
  // fraction of the reference surface's bounding-box diagonal.
  double amplitude_fraction = 0.1;
  int samples = 2;  // barycentric lattice order per triangle
};

// Relative Hausdorff distance between mode `ref_mode` on `ref` and
// `other_mode` on `other`, divided by ref.diagonal. A mode's sign is
// arbitrary, so both signs of other_mode are tried and the smaller distance
// is returned. InputError if a mode has the wrong length or is zero.
double mode_shape_distance(const ModeShapeSurface& ref, const VecX& ref_mode, const ModeShapeSurface& other,
                           const VecX& other_mode, const ModeDistanceOptions& options = {});

// Modes can change order between resolutions (close frequencies swap), so
// other mode i is compared with the reference modes j, |j - i| <= window,
// and matched to the one at the smallest distance. Each mode is matched on
// its own: two modes may pick the same reference mode, which then shows up
// as a large distance for one of them rather than as a forced pairing.
struct ModeMatch {
  int reference_mode = -1;
  double distance = 0.0;  // relative Hausdorff distance to it
};
std::vector<ModeMatch> match_modes(const ModeShapeSurface& ref, const MatX& ref_modes, const ModeShapeSurface& other,
                                   const MatX& other_modes, int window, const ModeDistanceOptions& options = {});

}  // namespace msfab
