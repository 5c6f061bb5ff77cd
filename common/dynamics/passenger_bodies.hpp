#pragma once
// Bodies that ride along during a static preload. A body with neither a
// clamped node nor a loaded node (a cube lying in a catapult's basket) has
// no static equilibrium of its own: it is held during the preload solve and
// then carried rigidly with what it rests on, i.e. moved by the best-fit
// rigid motion (rigid_body.hpp's projection with unit weights) of the other
// bodies' nodes that coincide with its own at rest. It starts the dynamics
// at rest in the loaded basket, as if placed there by hand.
#include <string>
#include <vector>

#include "dynamics/dynamics_scene.hpp"

namespace msfab {

// Per body of the scene: true for a passenger under the nodal load `load`.
std::vector<char> passenger_bodies(const DynamicsScene& scene, const VecX& load);

// Node-major 3N mask of the passengers' DOFs.
std::vector<char> passenger_dofs(const DynamicsScene& scene, const std::vector<char>& passenger);

// `solved` with every passenger moved from its initial positions by the
// rigid motion of its support between `initial` and `solved`. A passenger
// that touches no other body stays where it is; `notes` says which moved.
VecX carry_passengers(const DynamicsScene& scene, const std::vector<char>& passenger, const VecX& initial,
                      const VecX& solved, std::vector<std::string>* notes);

}  // namespace msfab
