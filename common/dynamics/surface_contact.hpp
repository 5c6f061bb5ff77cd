#pragma once
// Vertex-face proximity between boundary surfaces of a hex mesh: the
// candidates of the five-node contacts Gamma_k of thesis B.5, a boundary
// node p against a bilinear boundary quad (x_0..x_3) of another body or of
// its own body. The contact is linearized about the quad's closest point
// (s, t) and its outward normal n there:
//
//   gap = n . (x_p - sum_i w_i x_i),   w = bilinear weights of (s, t),
//
// which is linear in the displacements, so the contact row of G touches the
// five nodes with weights (1, -w_0, .., -w_3).
//
// Which pairs count. A node never touches a face it belongs to. A node may
// only touch a face whose closest point is interior (up to round-off): the
// closest point of a face beside a convex edge lies on the face's rim, in
// the face's plane, and would read as zero gap. The node's own surface must
// face the face (vertex normal . face normal < 0): a corner node resting on
// a top face also lies on the rim of the side face below it, at zero gap,
// and that side face must not hold it back. And the node must start the
// step on the outer side (gap >= -depth_limit): a node of the face's own
// element lies a whole element behind it.
//
// Edge-edge proximity (not in B.5, which has vertex-face contacts only):
// two boundary edges that cross, neither having a vertex over the other's
// faces, pass through each other unless their closest points are held
// apart. The contact is linearized about the closest points a(alpha) and
// b(beta) of the two lines and the common normal n = e_a x e_b there:
//
//   gap = n . ((1 - alpha) x_a0 + alpha x_a1 - (1 - beta) x_b0 - beta x_b1),
//
// again linear in the displacements, so the row of G touches the four nodes
// with weights (1 - alpha, alpha, beta - 1, -beta). n points from edge b to
// edge a: each edge's outward normal (the sum of its boundary faces'
// normals) must face the other edge (by a cosine of at least 1/4), which
// rules out edges seen through their own body and fixes the sign without looking at the gap (a resting
// contact has gap ~ 0 of either sign). Only pairs whose closest points are
// interior to both edges count (at an end point the vertex-face test
// applies), and nearly parallel edges are skipped: their common normal is
// ill-defined, and where they touch a vertex lies over a face.
#include <array>
#include <vector>

#include "core/types.hpp"
#include "fem/hex_boundary.hpp"

namespace msfab {

struct NodeFaceContact {
  int node = 0;
  int face = 0;                     // index into HexBoundary::faces
  std::array<double, 4> weights{};  // bilinear weights of the closest point
  Vec3 normal = Vec3::UnitZ();      // outward unit normal of the face there
  double gap_start = 0;             // the linearized gap at the start positions
  double gap_end = 0;               // ... at the end positions (same n and w)
};

// The closest point of the bilinear quad to p: parameters (s, t) clamped to
// [0, 1]^2 (Gauss-Newton on |x(s, t) - p|^2). `inside` tells whether the
// unclamped minimizer lies within `tolerance` of the unit square.
struct QuadProjection {
  double s = 0.5, t = 0.5;
  bool inside = false;
};
QuadProjection project_to_quad(const std::array<Vec3, 4>& x, const Vec3& p, double tolerance);

// Outward unit normal of a quad listed counter-clockwise from outside.
Vec3 quad_normal(const std::array<Vec3, 4>& x, double s, double t);

struct EdgeEdgeContact {
  int edge_a = 0, edge_b = 0;   // indices into BoundarySurface::edges(), edge_a < edge_b
  double alpha = 0, beta = 0;   // closest points' parameters along a and b
  Vec3 normal = Vec3::UnitZ();  // unit, from edge b towards edge a
  double gap_start = 0;         // the linearized gap at the start positions
  double gap_end = 0;           // ... at the end positions (same n, alpha, beta)
};

// A boundary edge: two nodes, and the boundary faces it borders (two on a
// manifold surface; more where bodies touch along an edge of one mesh).
struct BoundaryEdge {
  std::array<int, 2> nodes{};
  std::vector<int> faces;
};

// Parameters (alpha, beta) of the closest points of the lines through
// (a0, a1) and (b0, b1); false when the lines are parallel within
// `min_sine` (|e_a x e_b| < min_sine |e_a| |e_b|).
bool closest_line_parameters(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1, double min_sine,
                             double& alpha, double& beta);

class BoundarySurface {
 public:
  // `nodes`: the boundary nodes that may touch (clamped nodes left out).
  BoundarySurface(HexBoundary boundary, std::vector<int> nodes);

  // Node-face pairs whose linearized gap at `end` is below `margin` while
  // the node starts at gap >= -depth_limit, the face's closest point taken at
  // `end`. Per node, faces with nearly the same normal are represented by
  // the nearest one. Sorted by (node, face); `start` and `end` are 3N
  // position vectors.
  std::vector<NodeFaceContact> find(const VecX& start, const VecX& end, double margin, double depth_limit) const;

  // Edge pairs that do not share a node, whose closest points are interior
  // to both edges and whose linearized gap at `end` is below `margin` while
  // it starts at gap >= -depth_limit; n, alpha and beta taken at `end`.
  // Pairs whose four nodes are all outside `nodes` (clamped) never move
  // and are left out. Sorted by (edge_a, edge_b).
  std::vector<EdgeEdgeContact> find_edges(const VecX& start, const VecX& end, double margin, double depth_limit) const;

  const HexBoundary& boundary() const { return boundary_; }
  const std::vector<BoundaryEdge>& edges() const { return edges_; }

 private:
  HexBoundary boundary_;
  std::vector<int> nodes_;
  std::vector<BoundaryEdge> edges_;  // sorted by node pair
};

}  // namespace msfab
