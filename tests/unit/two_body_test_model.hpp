#pragma once
// The two-element contact scenes of the body-contact unit tests: body a is
// element 0, body b element 1, one stiff Neo-Hookean material, light
// stiffness damping, contact between and within bodies on.
#include <array>
#include <memory>
#include <vector>

#include "dynamics/dynamics_model.hpp"
#include "dynamics/newmark_integrator.hpp"
#include "fem/hex_mesh_bodies.hpp"
#include "material/neo_hookean.hpp"

namespace msfab::contact_test {

inline DynamicsModel two_body_model(const NodeArray& nodes, const std::vector<std::array<int, 8>>& elements) {
  DynamicsModel model;
  model.mesh = make_hex_mesh(nodes, elements, std::make_shared<NeoHookean>(1e7, 0.3));
  model.density.assign(2, 1000);
  model.damping_a.assign(2, 0.0);
  model.damping_b.assign(2, 1e-4);
  model.element_material_name = {"a", "b"};
  model.contact = true;
  model.body_contact = true;
  return model;
}

// Newmark at 0.1 ms steps, with or without edge-edge contact rows.
inline NewmarkOptions drop_options(bool edge_contact) {
  NewmarkOptions options;
  options.time_step = 1e-4;
  options.edge_contact = edge_contact;
  return options;
}

// Body b (nodes 8 to 15) set moving down at `speed`, at rest positions.
inline void drop_body_b(NewmarkIntegrator& sim, double speed) {
  VecX v = VecX::Zero(sim.assembler().num_dofs());
  for (int i = 8; i < 16; ++i) v(3 * i + 2) = -speed;
  sim.set_state(sim.assembler().rest_positions(), v);
}

}  // namespace msfab::contact_test
