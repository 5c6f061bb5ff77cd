#include "jump_observer.hpp"

#include "dynamics/mass_matrix.hpp"

namespace msfab {

JumpObserver::JumpObserver(const DynamicsScene& scene, const ObserverOptions& options)
    : scene_(scene),
      options_(options),
      body_(make_rigid_body(scalar_mass_matrix(scene.model.mesh, scene.model.density), scene.model.mesh.nodes)) {
  const VecX still = VecX::Zero(scene.initial_positions.size());
  R0_ = project_to_rigid(body_, scene.initial_positions, still).R;
  tolerance_ = options.touch * scene.grid.voxel_size;
  trajectory_.scene = scene.name;
  on_step(0.0, scene.initial_positions);
}

void JumpObserver::on_step(double time, const VecX& q) {
  TrajectorySample s;
  s.time = time;
  const RigidState r = project_to_rigid(body_, q, VecX::Zero(q.size()));
  s.center_of_mass = r.t;
  const Eigen::AngleAxisd rotation(r.R * R0_.transpose());
  s.rotation = rotation.angle() * rotation.axis();
  const int nodes = static_cast<int>(q.size() / 3);
  for (int i = 0; i < nodes; ++i)
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
