#include "dynamics/passenger_bodies.hpp"

#include <algorithm>
#include <cmath>

#include "dynamics/rigid_body.hpp"

namespace msfab {

namespace {

std::vector<int> node_bodies(const DynamicsScene& scene) {
  const HexMesh& mesh = scene.model.mesh;
  std::vector<int> body(mesh.num_nodes(), 0);
  for (int e = 0; e < mesh.num_elements(); ++e)
    for (int node : mesh.elements[e]) body[node] = scene.element_body.empty() ? 0 : scene.element_body[e];
  return body;
}

}  // namespace

std::vector<char> passenger_bodies(const DynamicsScene& scene, const VecX& load) {
  const int bodies = std::max<int>(1, static_cast<int>(scene.body_names.size()));
  std::vector<char> held(bodies, 0);
  const std::vector<int> body = node_bodies(scene);
  for (int i = 0; i < scene.model.mesh.num_nodes(); ++i) {
    const bool clamped = !scene.model.fixed.empty() && scene.model.fixed[3 * i];
    if (clamped || load.segment<3>(3 * i).squaredNorm() > 0) held[body[i]] = 1;
  }
  std::vector<char> passenger(bodies);
  for (int b = 0; b < bodies; ++b) passenger[b] = !held[b];
  return passenger;
}

std::vector<char> passenger_dofs(const DynamicsScene& scene, const std::vector<char>& passenger) {
  const std::vector<int> body = node_bodies(scene);
  std::vector<char> mask(3 * body.size(), 0);
  for (size_t i = 0; i < body.size(); ++i)
    if (passenger[body[i]]) mask[3 * i] = mask[3 * i + 1] = mask[3 * i + 2] = 1;
  return mask;
}

VecX carry_passengers(const DynamicsScene& scene, const std::vector<char>& passenger, const VecX& initial,
                      const VecX& solved, std::vector<std::string>* notes) {
  VecX q = solved;
  const HexMesh& mesh = scene.model.mesh;
  const std::vector<int> body = node_bodies(scene);
  const double tolerance = 1e-6 * scene.grid.voxel_size;
  for (int b = 0; b < static_cast<int>(passenger.size()); ++b) {
    if (!passenger[b]) continue;
    // Support: other bodies' nodes at a rest position of one of b's nodes
    // (separate_bodies duplicated them).
    std::vector<int> support;
    for (int i = 0; i < mesh.num_nodes(); ++i) {
      if (body[i] == b) continue;
      for (int j = 0; j < mesh.num_nodes(); ++j)
        if (body[j] == b && (mesh.nodes.row(i) - mesh.nodes.row(j)).norm() <= tolerance) {
          support.push_back(i);
          break;
        }
    }
    const std::string name = scene.body_names.empty() ? "body" : scene.body_names[b];
    // A line of support nodes fixes no rotation.
    NodeArray from(static_cast<Eigen::Index>(support.size()), 3);
    for (size_t k = 0; k < support.size(); ++k)
      from.row(Eigen::Index(k)) = initial.segment<3>(3 * support[k]).transpose();
    bool planar_or_solid = support.size() >= 3;
    if (planar_or_solid) {
      const Vec3 c = from.colwise().mean().transpose();
      Eigen::JacobiSVD<MatX> svd(from.rowwise() - c.transpose());
      planar_or_solid = svd.singularValues().size() >= 2 && svd.singularValues()(1) > 1e-9 * svd.singularValues()(0);
    }
    if (!planar_or_solid) {
      if (notes) notes->push_back(name + " rests on no supporting face and stays in place");
      continue;
    }
    SpMat unit(static_cast<Eigen::Index>(support.size()), static_cast<Eigen::Index>(support.size()));
    unit.setIdentity();
    const RigidBody patch = make_rigid_body(unit, from);
    VecX x0(3 * support.size()), x1(3 * support.size());
    for (size_t k = 0; k < support.size(); ++k) {
      x0.segment<3>(3 * k) = initial.segment<3>(3 * support[k]);
      x1.segment<3>(3 * k) = solved.segment<3>(3 * support[k]);
    }
    const VecX still = VecX::Zero(x0.size());
    const RigidState s0 = project_to_rigid(patch, x0, still), s1 = project_to_rigid(patch, x1, still);
    const Mat3 R = s1.R * s0.R.transpose();
    for (int i = 0; i < mesh.num_nodes(); ++i)
      if (body[i] == b) q.segment<3>(3 * i) = s1.t + R * (initial.segment<3>(3 * i) - s0.t);
    if (notes)
      notes->push_back(name + " carried with its support (" + std::to_string(support.size()) + " nodes, moved " +
                       std::to_string((s1.t - s0.t).norm() * 1e3) + " mm, turned " +
                       std::to_string(Eigen::AngleAxisd(R).angle() * 180 / M_PI) + " deg)");
  }
  return q;
}

}  // namespace msfab
