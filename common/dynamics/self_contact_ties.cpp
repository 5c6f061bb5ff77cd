#include "dynamics/self_contact_ties.hpp"

#include <algorithm>
#include <utility>

#include "fem/hex_boundary.hpp"

namespace msfab {

namespace {

Vec3 face_point(const SelfContactTie& t, const VecX& x) {
  Vec3 p = Vec3::Zero();
  for (int i = 0; i < 4; ++i) p += t.weight[i] * x.segment<3>(3 * t.face_nodes[i]);
  return p;
}

// Every boundary node may touch: the press clamps nothing.
BoundarySurface whole_boundary(const HexMesh& mesh) {
  HexBoundary boundary = hex_boundary(mesh);
  std::vector<int> nodes = boundary.nodes;
  return BoundarySurface(std::move(boundary), std::move(nodes));
}

}  // namespace

Vec3 SelfContactTie::face_normal(const VecX& x) const {
  std::array<Vec3, 4> corners;
  for (int i = 0; i < 4; ++i) corners[i] = x.segment<3>(3 * face_nodes[i]);
  // (s, t) from the bilinear weights ((1-s)(1-t), s(1-t), st, (1-s)t).
  return quad_normal(corners, weight[1] + weight[2], weight[2] + weight[3]);
}

SelfContactTies::SelfContactTies(const HexMesh& mesh)
    : surface_(whole_boundary(mesh)), slave_(mesh.num_nodes(), 0), master_count_(mesh.num_nodes(), 0) {}

bool SelfContactTies::tie(const NodeFaceContact& c, VecX& trial) {
  if (slave_[c.node] || master_count_[c.node] > 0) return false;
  SelfContactTie t;
  t.node = c.node;
  t.face = c.face;
  t.face_nodes = surface_.boundary().faces[c.face];
  t.weight = c.weights;
  for (int m : t.face_nodes)
    if (slave_[m]) return false;
  trial.segment<3>(3 * t.node) = face_point(t, trial);
  slave_[t.node] = 1;
  for (int m : t.face_nodes) ++master_count_[m];
  ties_.push_back(t);
  ++version_;
  return true;
}

VecX SelfContactTies::reduce(const VecX& g) const {
  VecX r = g;
  for (const SelfContactTie& t : ties_) {
    for (int i = 0; i < 4; ++i) r.segment<3>(3 * t.face_nodes[i]) += t.weight[i] * g.segment<3>(3 * t.node);
    r.segment<3>(3 * t.node).setZero();
  }
  return r;
}

SpMat SelfContactTies::reduce(const SpMat& K) const {
  const Eigen::Index n = K.rows();
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index d = 0; d < n; ++d)
    if (!slave_[d / 3]) entries.emplace_back(d, d, 1.0);
  for (const SelfContactTie& t : ties_)
    for (int i = 0; i < 4; ++i)
      for (int a = 0; a < 3; ++a) entries.emplace_back(3 * t.node + a, 3 * t.face_nodes[i] + a, t.weight[i]);
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
  for (const SelfContactTie& t : ties_) step.segment<3>(3 * t.node) = face_point(t, step);
}

int SelfContactTies::release(const VecX& q, const VecX& g, double threshold) {
  const size_t before = ties_.size();
  std::vector<SelfContactTie> kept;
  for (const SelfContactTie& t : ties_) {
    if (t.face_normal(q).dot(g.segment<3>(3 * t.node)) < -threshold) {
      slave_[t.node] = 0;
      for (int m : t.face_nodes) --master_count_[m];
    } else {
      kept.push_back(t);
    }
  }
  ties_ = std::move(kept);
  if (ties_.size() != before) ++version_;
  return static_cast<int>(before - ties_.size());
}

void SelfContactTies::record_reactions(const VecX& g) {
  for (SelfContactTie& t : ties_) t.reaction = g.segment<3>(3 * t.node);
}

void SelfContactTies::assign(const std::vector<SelfContactTie>& ties) {
  ties_ = ties;
  std::fill(slave_.begin(), slave_.end(), 0);
  std::fill(master_count_.begin(), master_count_.end(), 0);
  for (const SelfContactTie& t : ties_) {
    slave_[t.node] = 1;
    for (int m : t.face_nodes) ++master_count_[m];
  }
  ++version_;
}

bool SelfContactTies::penetrates(const VecX& q, const VecX& trial, double depth, double depth_limit) const {
  for (const NodeFaceContact& c : surface_.find(q, trial, -depth, depth_limit))
    if (!slave_[c.node]) return true;
  return false;
}

}  // namespace msfab
