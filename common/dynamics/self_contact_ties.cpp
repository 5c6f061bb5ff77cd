#include "dynamics/self_contact_ties.hpp"

#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <utility>

#include "core/errors.hpp"
#include "fem/hex_boundary.hpp"

namespace msfab {

namespace {

// Every boundary node may touch: the press clamps nothing.
BoundarySurface whole_boundary(const HexMesh& mesh) {
  HexBoundary boundary = hex_boundary(mesh);
  std::vector<int> nodes = boundary.nodes;
  return BoundarySurface(std::move(boundary), std::move(nodes));
}

Vec3 at(const VecX& x, int node) { return x.segment<3>(3 * node); }

}  // namespace

Vec3 SelfContactTie::face_normal(const VecX& x) const {
  std::array<Vec3, 4> corners;
  for (int i = 0; i < 4; ++i) corners[i] = at(x, face_nodes[i]);
  // (s, t) from the bilinear weights ((1-s)(1-t), s(1-t), st, (1-s)t).
  return quad_normal(corners, weight[1] + weight[2], weight[2] + weight[3]);
}

Vec3 SelfContactTie::push_normal(const VecX& x) const {
  if (!is_edge_pair()) return face_normal(x);
  const Vec3 ea = at(x, edge_nodes[1]) - at(x, edge_nodes[0]), eb = at(x, edge_nodes[3]) - at(x, edge_nodes[2]);
  Vec3 n = ea.cross(eb);
  // Edges turned nearly parallel have no common normal: the one they were
  // tied with stands in.
  if (!(n.norm() > 1e-3 * ea.norm() * eb.norm())) return edge_normal;
  n.normalize();
  return n.dot(edge_normal) < 0 ? Vec3(-n) : n;
}

std::vector<std::pair<int, double>> SelfContactTie::constraint() const {
  if (is_edge_pair())
    return {{edge_nodes[0], 1 - alpha}, {edge_nodes[1], alpha}, {edge_nodes[2], beta - 1}, {edge_nodes[3], -beta}};
  std::vector<std::pair<int, double>> terms{{node, 1.0}};
  for (int i = 0; i < 4; ++i) terms.emplace_back(face_nodes[i], -weight[i]);
  return terms;
}

SelfContactTies::SelfContactTies(const HexMesh& mesh, bool edge_contact)
    : surface_(whole_boundary(mesh)),
      edge_contact_(edge_contact),
      slave_(mesh.num_nodes(), 0),
      master_count_(mesh.num_nodes(), 0) {}

bool SelfContactTies::rebuild() {
  const size_t m = ties_.size();
  slave_rows_.assign(m, {});
  // A tie whose slave has the coefficient 1, appears in no other tie and
  // has no slave among its other nodes has a unit row and column in C_S: its
  // slave follows R = -C_M directly. The others (edge ties, and what they
  // touch) form the coupled block, solved together.
  std::vector<int> appearances(slave_.size(), 0);
  for (const SelfContactTie& t : ties_)
    for (const auto& term : t.constraint()) ++appearances[term.first];
  block_.clear();
  block_matrix_ = SpMat();
  for (size_t k = 0; k < m; ++k) {
    const SelfContactTie& t = ties_[k];
    bool coupled = false;
    for (const auto& [node, c] : t.constraint())
      if (node == t.node ? (c != 1.0 || appearances[node] != 1) : slave_[node] != 0) coupled = true;
    if (coupled) {
      block_.push_back(static_cast<int>(k));
    } else {
      for (const auto& [node, c] : t.constraint())
        if (node != t.node) slave_rows_[k].emplace_back(node, -c);
    }
  }
  const std::vector<int>& block = block_;
  if (block.empty()) return true;
  // The coupled ties' slaves appear only in coupled ties (a slave in another
  // tie makes both coupled), so the block is closed.
  const int b = static_cast<int>(block.size());
  std::vector<int> slave_index(slave_.size(), -1), master_column(slave_.size(), -1);
  std::vector<int> masters;
  for (int r = 0; r < b; ++r) slave_index[ties_[block[r]].node] = r;
  std::vector<Eigen::Triplet<double>> cs;
  for (int r = 0; r < b; ++r)
    for (const auto& [node, c] : ties_[block[r]].constraint())
      if (slave_index[node] >= 0) {
        cs.emplace_back(r, slave_index[node], c);
      } else if (master_column[node] < 0) {
        master_column[node] = static_cast<int>(masters.size());
        masters.push_back(node);
      }
  block_matrix_.resize(b, b);
  block_matrix_.setFromTriplets(cs.begin(), cs.end());
  const SpMat& CS = block_matrix_;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(b, masters.size());
  for (int r = 0; r < b; ++r)
    for (const auto& [node, c] : ties_[block[r]].constraint())
      if (slave_index[node] < 0) rhs(r, master_column[node]) -= c;
  Eigen::SparseLU<SpMat> lu(CS);
  if (lu.info() != Eigen::Success) return false;
  const Eigen::MatrixXd R = lu.solve(rhs);
  if (lu.info() != Eigen::Success || !R.allFinite() || R.cwiseAbs().maxCoeff() > kMaxTieWeight) return false;
  // Weights that only round-off made nonzero are dropped: they would widen
  // the reduced pattern for nothing.
  const double drop = 1e-14 * std::max(1.0, R.cwiseAbs().maxCoeff());
  for (int r = 0; r < b; ++r)
    for (size_t j = 0; j < masters.size(); ++j)
      if (std::abs(R(r, j)) > drop) slave_rows_[block[r]].emplace_back(masters[j], R(r, j));
  return true;
}

bool SelfContactTies::tie(const NodeFaceContact& c, VecX& trial) {
  if (slave_[c.node] || master_count_[c.node] > 0) return false;
  SelfContactTie t;
  t.node = c.node;
  t.face = c.face;
  t.face_nodes = surface_.boundary().faces[c.face];
  t.weight = c.weights;
  for (int m : t.face_nodes)
    if (slave_[m]) return false;
  // The node is in no other tie and its face holds no slave, so C_S gains
  // a unit row and column; add_tie checks all the same.
  return add_tie(t, trial);
}

SelfContactTie SelfContactTies::edge_tie(const EdgeEdgeContact& c) const {
  SelfContactTie t;
  t.face = -1;
  const auto& ea = surface_.edges()[c.edge_a].nodes;
  const auto& eb = surface_.edges()[c.edge_b].nodes;
  t.edge_nodes = {ea[0], ea[1], eb[0], eb[1]};
  t.edges = {c.edge_a, c.edge_b};
  t.alpha = c.alpha;
  t.beta = c.beta;
  t.edge_normal = c.normal;
  return t;
}

std::vector<int> SelfContactTies::edge_slave_candidates(const SelfContactTie& t) const {
  const int a = t.alpha <= 0.5 ? t.edge_nodes[0] : t.edge_nodes[1];
  const int b = t.beta <= 0.5 ? t.edge_nodes[2] : t.edge_nodes[3];
  const double wa = std::max(t.alpha, 1 - t.alpha), wb = std::max(t.beta, 1 - t.beta);
  std::vector<int> out = wa >= wb ? std::vector<int>{a, b} : std::vector<int>{b, a};
  out.erase(std::remove_if(out.begin(), out.end(), [&](int n) { return slave_[n] != 0; }), out.end());
  return out;
}

bool SelfContactTies::add_tie(const SelfContactTie& t, VecX& trial) {
  std::vector<SelfContactTie> more = ties_;
  more.push_back(t);
  if (!set_ties(std::move(more))) {
    more = ties_;
    more.pop_back();
    set_ties(std::move(more));  // the set before, which was valid
    return false;
  }
  // A new edge tie's slave may have been a master: every slave is put where
  // its masters put it. A node-face tie changes no other slave's row.
  for (size_t k = t.is_edge_pair() ? 0 : ties_.size() - 1; k < ties_.size(); ++k) {
    Vec3 p = Vec3::Zero();
    for (const auto& [node, w] : slave_rows_[k]) p += w * at(trial, node);
    trial.segment<3>(3 * ties_[k].node) = p;
  }
  ++version_;
  return true;
}

bool SelfContactTies::set_ties(std::vector<SelfContactTie> ties) {
  ties_ = std::move(ties);
  std::fill(slave_.begin(), slave_.end(), 0);
  std::fill(master_count_.begin(), master_count_.end(), 0);
  tied_edges_.clear();
  for (const SelfContactTie& t : ties_) {
    slave_[t.node] = t.is_edge_pair() ? kEdgeSlave : kFaceSlave;
    for (const auto& term : t.constraint())
      if (term.first != t.node) ++master_count_[term.first];
    if (t.is_edge_pair()) tied_edges_.insert({t.edges[0], t.edges[1]});
  }
  return rebuild();
}

VecX SelfContactTies::reduce(const VecX& g) const {
  VecX r = g;
  for (size_t k = 0; k < ties_.size(); ++k) {
    const int s = ties_[k].node;
    for (const auto& [node, w] : slave_rows_[k]) r.segment<3>(3 * node) += w * g.segment<3>(3 * s);
    r.segment<3>(3 * s).setZero();
  }
  return r;
}

SpMat SelfContactTies::reduce(const SpMat& K) const {
  const Eigen::Index n = K.rows();
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index d = 0; d < n; ++d)
    if (!slave_[d / 3]) entries.emplace_back(d, d, 1.0);
  for (size_t k = 0; k < ties_.size(); ++k)
    for (const auto& [node, w] : slave_rows_[k])
      for (int a = 0; a < 3; ++a) entries.emplace_back(3 * ties_[k].node + a, 3 * node + a, w);
  SpMat T(n, n);
  T.setFromTriplets(entries.begin(), entries.end());
  SpMat identity_on_slaves(n, n);
  entries.clear();
  for (Eigen::Index d = 0; d < n; ++d)
    if (slave_[d / 3]) entries.emplace_back(d, d, 1.0);
  identity_on_slaves.setFromTriplets(entries.begin(), entries.end());
  SpMat reduced = SpMat(T.transpose() * K * T) + identity_on_slaves;
  reduced.makeCompressed();
  return reduced;
}

void SelfContactTies::expand(VecX& step) const {
  for (size_t k = 0; k < ties_.size(); ++k) {
    Vec3 p = Vec3::Zero();
    for (const auto& [node, w] : slave_rows_[k]) p += w * at(step, node);
    step.segment<3>(3 * ties_[k].node) = p;
  }
}

std::vector<Vec3> SelfContactTies::forces(const VecX& g) const {
  std::vector<Vec3> lambda(ties_.size());
  for (size_t k = 0; k < ties_.size(); ++k) lambda[k] = at(g, ties_[k].node);  // a unit row and column of C_S
  if (block_.empty()) return lambda;
  // g_S = C_S^T lambda over the coupled block: the slaves' equilibrium with
  // the ties' forces.
  const int b = static_cast<int>(block_.size());
  Eigen::MatrixXd gs(b, 3);
  for (int r = 0; r < b; ++r) gs.row(r) = lambda[block_[r]].transpose();
  const SpMat transposed = block_matrix_.transpose();
  Eigen::SparseLU<SpMat> lu(transposed);
  const Eigen::MatrixXd l = lu.solve(gs);
  for (int r = 0; r < b; ++r) lambda[block_[r]] = l.row(r).transpose();
  return lambda;
}

int SelfContactTies::release(const VecX& q, const VecX& g, double threshold) {
  const size_t before = ties_.size();
  const std::vector<Vec3> lambda = forces(g);
  std::vector<SelfContactTie> kept;
  for (size_t k = 0; k < before; ++k)
    if (!(ties_[k].push_normal(q).dot(lambda[k]) < -threshold)) kept.push_back(ties_[k]);
  if (kept.size() == before) return 0;
  if (!set_ties(kept)) {
    // What is left of a coupled set can be singular although the whole was
    // not: its edge ties go too (node-face ties alone always rebuild), and
    // are made again where the edges still cross.
    std::vector<SelfContactTie> face_ties;
    for (const SelfContactTie& t : kept)
      if (!t.is_edge_pair()) face_ties.push_back(t);
    set_ties(std::move(face_ties));
  }
  ++version_;
  return static_cast<int>(before - ties_.size());
}

void SelfContactTies::record_reactions(const VecX& g) {
  const std::vector<Vec3> lambda = forces(g);
  for (size_t k = 0; k < ties_.size(); ++k) ties_[k].reaction = lambda[k];
}

void SelfContactTies::assign(const std::vector<SelfContactTie>& ties) {
  if (!set_ties(ties)) throw NumericalError("self-contact: a restored tie set makes the slaves' coefficients singular");
  ++version_;
}

bool SelfContactTies::penetrates(const VecX& q, const VecX& trial, double depth, double depth_limit) const {
  // A node tied to a face follows it; a slave of an edge tie is held only
  // at its edge's crossing and must not go through a face either.
  for (const NodeFaceContact& c : surface_.find(q, trial, -depth, depth_limit))
    if (slave_[c.node] != kFaceSlave) return true;
  if (edge_contact_)
    for (const EdgeEdgeContact& c : surface_.find_edges(q, trial, -depth, depth_limit))
      if (!tied_edges_.count({c.edge_a, c.edge_b})) return true;
  return false;
}

}  // namespace msfab
