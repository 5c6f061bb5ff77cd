#pragma once
// No-slip self-contact for the quasistatic press: a boundary node that
// reaches a boundary face of the mesh (another body's or its own) is put on
// the face and tied to the face's material point there,
//
//   x_p = sum_i w_i x_i,   w = bilinear weights of the touching point,
//
// the counterpart between deformable surfaces of the obstacle contact of
// B.3, which holds a vertex where it touched (infinite friction). Two
// boundary edges that cross (surface_contact.hpp: neither has a vertex over
// the other's faces, so no node-face tie can hold them) are tied the same
// way at their closest points,
//
//   (1 - alpha) x_a0 + alpha x_a1 = (1 - beta) x_b0 + beta x_b1.
//
// Every tie is a linear multi-point constraint sum_k c_k x_k = 0 with one
// of its nodes the tie's slave, eliminated from the Newton system: with C_S
// the coefficients of the slaves and C_M those of the other nodes, x_S = R
// x_M, R = -C_S^-1 C_M, so x = T y with y the unknowns of every other node,
// the step solves T^T K T y = -T^T g and the slaves follow exactly. The
// force each tie carries is lambda = C_S^-T g_S (g_S: the slaves' gradient,
// their own equilibrium): the force of the face on its node, or of edge b
// on edge a. A tie is released when it would pull: n . lambda < 0 with n
// the face's outward normal, or the edges' common normal from b towards a.
//
// A node-face tie is made only for a node that is in no other tie, on a face
// with no slave, so node-face ties alone give C_S = I (R is the face
// weights). An edge tie's slave is the node of larger weight on one of its
// edges (|c| >= 1/2, so R stays bounded) that is no slave yet; it may be
// another tie's master, and its other nodes may be slaves. The ties that
// do not have a unit row and column in C_S form a block solved together; a
// tie that would make it singular or R larger than kMaxTieWeight is not
// made. A release that leaves the block singular releases its edge ties
// too. A slave of an edge tie is held only where its edges cross: it may
// neither go through a face nor be tied to one, and an obstacle does not
// hold it (the press then halves its steps rather than let it through).
#include <array>
#include <set>
#include <utility>
#include <vector>

#include "core/types.hpp"
#include "dynamics/surface_contact.hpp"
#include "fem/hex_mesh.hpp"

namespace msfab {

struct SelfContactTie {
  int node = 0;  // the slave: the node on the face, or one of the edge pair's four nodes
  int face = 0;  // index into the boundary's faces; -1 for an edge pair
  std::array<int, 4> face_nodes{};
  std::array<double, 4> weight{};  // bilinear weights of the point the node is tied to
  // Edge pair (face == -1): edges (a0, a1), (b0, b1) held together at
  // parameters alpha along a and beta along b.
  std::array<int, 4> edge_nodes{};   // a0, a1, b0, b1
  std::array<int, 2> edges{-1, -1};  // indices into the boundary's edges, a < b
  double alpha = 0, beta = 0;
  Vec3 edge_normal = Vec3::UnitZ();  // from edge b towards edge a when tied (fixes the sign)
  // Force the face exerts on the node, or edge b on edge a (set by the solver).
  Vec3 reaction = Vec3::Zero();

  bool is_edge_pair() const { return face < 0; }
  // The face's outward unit normal at the tied point, face corners at `x`
  // (node-face ties).
  Vec3 face_normal(const VecX& x) const;
  // The direction along which the tie pushes at `x`: the face's outward
  // normal, or the edges' common normal from b towards a.
  Vec3 push_normal(const VecX& x) const;
  // The constraint sum_k c_k x_k = 0: up to five (node, c_k).
  std::vector<std::pair<int, double>> constraint() const;
};

// Largest |R| entry of a tie set: beyond it the slaves' coefficients are
// near-singular and the tie is not made.
constexpr double kMaxTieWeight = 1e3;

class SelfContactTies {
 public:
  // edge_contact: tie crossing edges too.
  explicit SelfContactTies(const HexMesh& mesh, bool edge_contact = true);

  const std::vector<SelfContactTie>& ties() const { return ties_; }
  bool empty() const { return ties_.empty(); }
  // Changes whenever a tie is made or released (the reduced matrix's
  // pattern depends on the set).
  int version() const { return version_; }
  bool is_slave(int node) const { return slave_[node] != 0; }

  // T^T g: each slave's entries moved onto its masters with R's weights,
  // the slave's own entries zero.
  VecX reduce(const VecX& g) const;
  // T^T K T plus the identity on the slave DOFs (their rows stay in the
  // system, decoupled).
  SpMat reduce(const SpMat& K) const;
  // Sets each slave's entries of a step from its masters.
  void expand(VecX& step) const;

  // Replaces the ties by an earlier set (a failed load increment is
  // retried from its start).
  void assign(const std::vector<SelfContactTie>& ties);

  // Releases the ties whose force would pull (n . lambda < -threshold, n at
  // `q`); returns how many.
  int release(const VecX& q, const VecX& g, double threshold);
  // Stores each tie's force lambda.
  void record_reactions(const VecX& g);
  // Whether a node that is not tied ends deeper than `depth` behind a face,
  // or two edges not tied to each other cross deeper than `depth`, on the
  // way from `q` to `trial` (starting no deeper than `depth_limit`).
  bool penetrates(const VecX& q, const VecX& trial, double depth, double depth_limit) const;
  // Nodes that are not tied and end closer than `margin` to a face (behind
  // it for margin 0) on the way from `q` to `trial`, starting no deeper than
  // `depth_limit` at `q`, are put on the face in `trial` and tied, unless
  // `held(node)` (an obstacle holds it) or the rules above forbid it; then
  // crossing edges alike. Returns how many ties were made. `trial` may be
  // `q` itself.
  template <class Held>
  int activate(const VecX& q, VecX& trial, double margin, double depth_limit, Held held) {
    int made = 0;
    for (const NodeFaceContact& c : surface_.find(q, trial, margin, depth_limit))
      if (!held(c.node) && tie(c, trial)) ++made;
    if (edge_contact_)
      for (const EdgeEdgeContact& c : surface_.find_edges(q, trial, margin, depth_limit))
        if (tie_edges(c, trial, held)) ++made;
    return made;
  }

 private:
  bool tie(const NodeFaceContact& c, VecX& trial);
  template <class Held>
  bool tie_edges(const EdgeEdgeContact& c, VecX& trial, Held held) {
    if (tied_edges_.count({c.edge_a, c.edge_b})) return false;
    SelfContactTie t = edge_tie(c);
    for (int slave : edge_slave_candidates(t)) {
      t.node = slave;
      if (!held(slave) && add_tie(t, trial)) return true;
    }
    return false;
  }
  SelfContactTie edge_tie(const EdgeEdgeContact& c) const;
  // The nodes of larger weight on each edge, the larger first.
  std::vector<int> edge_slave_candidates(const SelfContactTie& t) const;
  // Adds `t`; false (nothing changed) where C_S becomes singular or R too
  // large. Puts every slave of `trial` where its masters put it.
  bool add_tie(const SelfContactTie& t, VecX& trial);
  // Replaces the ties, deriving the slaves, master counts and tied edges,
  // and rebuilds R; false where that fails (the set is kept all the same).
  bool set_ties(std::vector<SelfContactTie> ties);
  // R from the ties; false where C_S is singular or R too large.
  bool rebuild();
  // Each tie's force lambda = C_S^-T g_S.
  std::vector<Vec3> forces(const VecX& g) const;

  BoundarySurface surface_;
  bool edge_contact_ = true;
  std::vector<SelfContactTie> ties_;
  static constexpr char kFaceSlave = 1, kEdgeSlave = 2;
  std::vector<char> slave_;        // per node: 0, or the kind of tie it is the slave of
  std::vector<int> master_count_;  // ties each node is a master of
  std::set<std::pair<int, int>> tied_edges_;
  // R: per tie, its slave's masters and weights.
  std::vector<std::vector<std::pair<int, double>>> slave_rows_;
  // The ties of the coupled block of C_S (those without a unit row and
  // column), and that block's matrix.
  std::vector<int> block_;
  SpMat block_matrix_;
  int version_ = 0;  // only grows, so no two sets share a version
};

}  // namespace msfab
