#pragma once
// No-slip self-contact for the quasistatic press: a boundary node that
// reaches a boundary face of the mesh (another body's or its own) is put on
// the face and tied to the face's material point there,
//
//   x_p = sum_i w_i x_i,   w = bilinear weights of the touching point,
//
// the counterpart between deformable surfaces of the obstacle contact of
// B.3, which holds a vertex where it touched (infinite friction). The tie is
// a linear multi-point constraint, eliminated from the Newton system as a
// slave node: x = T y with y the unknowns of every other node, so the step
// solves T^T K T y = -T^T g and the slave follows its face exactly. The
// force the face exerts on the node is its gradient g_p (the node's own
// equilibrium), the reaction the tie releases on when it pulls:
// n . g_p < 0 with n the face's outward normal.
//
// To keep T one level deep, a node that is the master of a tie (a corner of
// a face holding a node) never becomes a slave, and a face with a slave
// node holds no other node.
#include <array>
#include <vector>

#include "core/types.hpp"
#include "dynamics/surface_contact.hpp"
#include "fem/hex_mesh.hpp"

namespace msfab {

struct SelfContactTie {
  int node = 0;
  int face = 0;  // index into the boundary's faces
  std::array<int, 4> face_nodes{};
  std::array<double, 4> weight{};  // bilinear weights of the point the node is tied to
  Vec3 reaction = Vec3::Zero();    // force the face exerts on the node (set by the solver)

  // The face's outward unit normal at the tied point, face corners at `x`.
  Vec3 face_normal(const VecX& x) const;
};

class SelfContactTies {
 public:
  explicit SelfContactTies(const HexMesh& mesh);

  const std::vector<SelfContactTie>& ties() const { return ties_; }
  bool empty() const { return ties_.empty(); }
  // Changes whenever a tie is made or released (the reduced matrix's
  // pattern depends on the set).
  int version() const { return version_; }
  bool is_slave(int node) const { return slave_[node] != 0; }

  // T^T g: each slave's entries moved onto its face's nodes with the tie's
  // weights, the slave's own entries zero.
  VecX reduce(const VecX& g) const;
  // T^T K T plus the identity on the slave DOFs (their rows stay in the
  // system, decoupled).
  SpMat reduce(const SpMat& K) const;
  // Sets each slave's entries of a step from its face's nodes.
  void expand(VecX& step) const;

  // Replaces the ties by an earlier set (a failed load increment is
  // retried from its start).
  void assign(const std::vector<SelfContactTie>& ties);

  // Releases the ties whose reaction g_p pulls the node off its face
  // (n . g_p < -threshold, n at `q`); returns how many.
  int release(const VecX& q, const VecX& g, double threshold);
  // Stores each tie's reaction g_p.
  void record_reactions(const VecX& g);
  // Whether a node that is not tied ends deeper than `depth` behind a face
  // on the way from `q` to `trial` (starting no deeper than `depth_limit`).
  bool penetrates(const VecX& q, const VecX& trial, double depth, double depth_limit) const;
  // Nodes that are not tied and end closer than `margin` to a face (behind
  // it for margin 0) on the way from `q` to `trial`, starting no deeper than
  // `depth_limit` at `q`: each is put on the face in `trial` and tied,
  // unless `held(node)` (an obstacle holds it) or the rules above forbid
  // it. Returns how many were tied. `trial` may be `q` itself.
  template <class Held>
  int activate(const VecX& q, VecX& trial, double margin, double depth_limit, Held held) {
    int made = 0;
    for (const NodeFaceContact& c : surface_.find(q, trial, margin, depth_limit))
      if (!held(c.node) && tie(c, trial)) ++made;
    return made;
  }

 private:
  bool tie(const NodeFaceContact& c, VecX& trial);

  BoundarySurface surface_;
  std::vector<SelfContactTie> ties_;
  std::vector<char> slave_;
  std::vector<int> master_count_;  // ties each node is a face corner of
  int version_ = 0;                // only grows, so no two sets share a version
};

}  // namespace msfab
