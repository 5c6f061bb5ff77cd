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
  Vec3 n = (at(x, edge_nodes[1]) - at(x, edge_nodes[0])).cross(at(x, edge_nodes[3]) - at(x, edge_nodes[2]));
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
  // C_S is the identity unless a tie's slave has a coefficient other than 1
  // or appears in another tie.
  coupled_ = false;
  for (const SelfContactTie& t : ties_)
    for (const auto& [node, c] : t.constraint())
      if ((node == t.node && c != 1.0) || (node != t.node && slave_[node])) coupled_ = true;
  if (!coupled_) {
    for (size_t k = 0; k < m; ++k)
      for (const auto& [node, c] : ties_[k].constraint())
        if (node != ties_[k].node) slave_rows_[k].emplace_back(node, -c);
    return true;
  }
  std::vector<int> slave_index(slave_.size(), -1), master_column(slave_.size(), -1);
  std::vector<int> masters;
  for (size_t k = 0; k < m; ++k) slave_index[ties_[k].node] = static_cast<int>(k);
  std::vector<Eigen::Triplet<double>> cs;
  for (size_t k = 0; k < m; ++k)
    for (const auto& [node, c] : ties_[k].constraint())
      if (slave_index[node] >= 0) {
        cs.emplace_back(static_cast<int>(k), slave_index[node], c);
      } else if (master_column[node] < 0) {
        master_column[node] = static_cast<int>(masters.size());
        masters.push_back(node);
      }
  SpMat CS(m, m);
  CS.setFromTriplets(cs.begin(), cs.end());
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m, masters.size());
  for (size_t k = 0; k < m; ++k)
    for (const auto& [node, c] : ties_[k].constraint())
      if (slave_index[node] < 0) rhs(k, master_column[node]) -= c;
  Eigen::SparseLU<SpMat> lu(CS);
  if (lu.info() != Eigen::Success) return false;
  const Eigen::MatrixXd R = lu.solve(rhs);
  if (lu.info() != Eigen::Success || !R.allFinite() || R.cwiseAbs().maxCoeff() > kMaxTieWeight) return false;
  // Weights that only round-off made nonzero are dropped: they would widen
  // the reduced pattern for nothing.
  const double drop = 1e-14 * std::max(1.0, R.cwiseAbs().maxCoeff());
  for (size_t k = 0; k < m; ++k)
    for (size_t j = 0; j < masters.size(); ++j)
      if (std::abs(R(k, j)) > drop) slave_rows_[k].emplace_back(masters[j], R(k, j));
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
  slave_[t.node] = 1;
  for (int m : t.face_nodes) ++master_count_[m];
  ties_.push_back(t);
  // The node is in no other tie and its face holds no slave, so C_S gains
  // an identity row and column; checked all the same.
  if (!rebuild()) {
    ties_.pop_back();
    slave_[t.node] = 0;
    for (int m : t.face_nodes) --master_count_[m];
    rebuild();
    return false;
  }
  Vec3 p = Vec3::Zero();
  for (int i = 0; i < 4; ++i) p += t.weight[i] * at(trial, t.face_nodes[i]);
  trial.segment<3>(3 * t.node) = p;
  ++version_;
  return true;
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

bool SelfContactTies::add_edge_tie(SelfContactTie t, int slave, VecX& trial) {
  t.node = slave;
  ties_.push_back(t);
  slave_[slave] = 1;
  for (int n : t.edge_nodes)
    if (n != slave) ++master_count_[n];
  if (!rebuild()) {
    ties_.pop_back();
    slave_[slave] = 0;
    for (int n : t.edge_nodes)
      if (n != slave) --master_count_[n];
    rebuild();  // the set before, which was valid
    return false;
  }
  tied_edges_.insert({t.edges[0], t.edges[1]});
  // A new slave may have been a master: every slave is put where its
  // masters put it.
  for (size_t k = 0; k < ties_.size(); ++k) {
    Vec3 p = Vec3::Zero();
    for (const auto& [node, w] : slave_rows_[k]) p += w * at(trial, node);
    trial.segment<3>(3 * ties_[k].node) = p;
  }
  ++version_;
  return true;
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
  const size_t m = ties_.size();
  std::vector<Vec3> lambda(m);
  if (!coupled_) {
    for (size_t k = 0; k < m; ++k) lambda[k] = at(g, ties_[k].node);
    return lambda;
  }
  // g_S = C_S^T lambda: the slaves' equilibrium with the ties' forces.
  std::vector<int> slave_index(slave_.size(), -1);
  for (size_t k = 0; k < m; ++k) slave_index[ties_[k].node] = static_cast<int>(k);
  std::vector<Eigen::Triplet<double>> cst;
  for (size_t k = 0; k < m; ++k)
    for (const auto& [node, c] : ties_[k].constraint())
      if (slave_index[node] >= 0) cst.emplace_back(slave_index[node], static_cast<int>(k), c);
  SpMat CST(m, m);
  CST.setFromTriplets(cst.begin(), cst.end());
  Eigen::MatrixXd gs(m, 3);
  for (size_t k = 0; k < m; ++k) gs.row(k) = at(g, ties_[k].node).transpose();
  Eigen::SparseLU<SpMat> lu(CST);
  const Eigen::MatrixXd l = lu.solve(gs);
  for (size_t k = 0; k < m; ++k) lambda[k] = l.row(k).transpose();
  return lambda;
}

int SelfContactTies::release(const VecX& q, const VecX& g, double threshold) {
  const size_t before = ties_.size();
  const std::vector<Vec3> lambda = forces(g);
  std::vector<SelfContactTie> kept;
  for (size_t k = 0; k < before; ++k) {
    const SelfContactTie& t = ties_[k];
    if (t.push_normal(q).dot(lambda[k]) < -threshold) {
      slave_[t.node] = 0;
      for (const auto& term : t.constraint())
        if (term.first != t.node) --master_count_[term.first];
      if (t.is_edge_pair()) tied_edges_.erase({t.edges[0], t.edges[1]});
    } else {
      kept.push_back(t);
    }
  }
  if (kept.size() == before) return 0;
  ties_ = std::move(kept);
  if (!rebuild())
    throw NumericalError("self-contact: the ties left after a release make the slaves' coefficients singular");
  ++version_;
  return static_cast<int>(before - ties_.size());
}

void SelfContactTies::record_reactions(const VecX& g) {
  const std::vector<Vec3> lambda = forces(g);
  for (size_t k = 0; k < ties_.size(); ++k) ties_[k].reaction = lambda[k];
}

void SelfContactTies::assign(const std::vector<SelfContactTie>& ties) {
  ties_ = ties;
  std::fill(slave_.begin(), slave_.end(), 0);
  std::fill(master_count_.begin(), master_count_.end(), 0);
  tied_edges_.clear();
  for (const SelfContactTie& t : ties_) {
    slave_[t.node] = 1;
    for (const auto& term : t.constraint())
      if (term.first != t.node) ++master_count_[term.first];
    if (t.is_edge_pair()) tied_edges_.insert({t.edges[0], t.edges[1]});
  }
  if (!rebuild()) throw NumericalError("self-contact: a restored tie set makes the slaves' coefficients singular");
  ++version_;
}

bool SelfContactTies::penetrates(const VecX& q, const VecX& trial, double depth, double depth_limit) const {
  for (const NodeFaceContact& c : surface_.find(q, trial, -depth, depth_limit))
    if (!slave_[c.node]) return true;
  if (edge_contact_)
    for (const EdgeEdgeContact& c : surface_.find_edges(q, trial, -depth, depth_limit))
      if (!tied_edges_.count({c.edge_a, c.edge_b})) return true;
  return false;
}

}  // namespace msfab
