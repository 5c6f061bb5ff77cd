#include "jump_observer.hpp"

#include <algorithm>

#include "core/errors.hpp"
#include "dynamics/mass_matrix.hpp"

namespace msfab {

namespace {

// The nodes of the named body (all nodes when `name` is empty).
std::vector<int> body_nodes(const DynamicsScene& scene, const std::string& name) {
  const HexMesh& mesh = scene.model.mesh;
  std::vector<int> nodes;
  if (name.empty()) {
    for (int i = 0; i < mesh.num_nodes(); ++i) nodes.push_back(i);
    return nodes;
  }
  const auto it = std::find(scene.body_names.begin(), scene.body_names.end(), name);
  if (it == scene.body_names.end()) throw InputError("measure.body = " + name + ": the scene has no body of that name");
  const int b = static_cast<int>(it - scene.body_names.begin());
  std::vector<char> in(mesh.num_nodes(), 0);
  for (int e = 0; e < mesh.num_elements(); ++e)
    if (scene.element_body[e] == b)
      for (int n : mesh.elements[e]) in[n] = 1;
  for (int i = 0; i < mesh.num_nodes(); ++i)
    if (in[i]) nodes.push_back(i);
  return nodes;
}

VecX gather(const VecX& q, const std::vector<int>& nodes) {
  VecX out(3 * nodes.size());
  for (size_t k = 0; k < nodes.size(); ++k) out.segment<3>(3 * k) = q.segment<3>(3 * nodes[k]);
  return out;
}

// Bodies share no node, so a body's mass matrix is the block of its nodes.
RigidBody measured_body(const DynamicsScene& scene, const std::vector<int>& nodes) {
  const SpMat m = scalar_mass_matrix(scene.model.mesh, scene.model.density);
  std::vector<int> local(scene.model.mesh.num_nodes(), -1);
  for (size_t k = 0; k < nodes.size(); ++k) local[nodes[k]] = static_cast<int>(k);
  std::vector<Eigen::Triplet<double>> entries;
  for (int j = 0; j < m.outerSize(); ++j)
    for (SpMat::InnerIterator it(m, j); it; ++it)
      if (local[it.row()] >= 0 && local[it.col()] >= 0)
        entries.emplace_back(local[it.row()], local[it.col()], it.value());
  SpMat sub(static_cast<Eigen::Index>(nodes.size()), static_cast<Eigen::Index>(nodes.size()));
  sub.setFromTriplets(entries.begin(), entries.end());
  NodeArray rest(static_cast<Eigen::Index>(nodes.size()), 3);
  for (size_t k = 0; k < nodes.size(); ++k) rest.row(Eigen::Index(k)) = scene.model.mesh.nodes.row(nodes[k]);
  return make_rigid_body(sub, rest);
}

}  // namespace

JumpObserver::JumpObserver(const DynamicsScene& scene, const ObserverOptions& options)
    : scene_(scene), options_(options), nodes_(body_nodes(scene, options.body)), body_(measured_body(scene, nodes_)) {
  const VecX still = VecX::Zero(3 * nodes_.size());
  R0_ = project_to_rigid(body_, gather(scene.initial_positions, nodes_), still).R;
  tolerance_ = options.touch * scene.grid.voxel_size;
  trajectory_.scene = scene.name;
  on_step(0.0, scene.initial_positions);
}

void JumpObserver::on_step(double time, const VecX& q) {
  TrajectorySample s;
  s.time = time;
  const VecX x = gather(q, nodes_);
  const RigidState r = project_to_rigid(body_, x, VecX::Zero(x.size()));
  s.center_of_mass = r.t;
  const Eigen::AngleAxisd rotation(r.R * R0_.transpose());
  s.rotation = rotation.angle() * rotation.axis();
  for (int i : nodes_)
    for (const Obstacle& o : scene_.model.obstacles)
      if (signed_distance(o, q.segment<3>(3 * i), nullptr) < tolerance_) {
        ++s.active_contacts;
        break;
      }
  s.contacts = s.active_contacts;
  trajectory_.samples.push_back(s);

  if (s.active_contacts == 0) {
    if (airborne_since_ < 0) airborne_since_ = time;
  } else {
    if (landed_at_ < 0 && airborne_since_ >= 0 && time - airborne_since_ >= options_.min_flight) landed_at_ = time;
    airborne_since_ = -1;
  }
  if (landed_at_ >= 0 && time - landed_at_ >= options_.settle) throw JumpOver{};
}

}  // namespace msfab
