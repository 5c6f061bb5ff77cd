#pragma once
// What the dynamic integrator simulates: one hex mesh (it may hold several
// disconnected bodies) with per-element density and Rayleigh damping, uniform
// gravity, optional clamped nodes, static obstacles with a friction table,
// and the impact model. A scene switches each phenomenon on only when it
// needs it ("model only what a scene needs"): contact and friction cost
// linear solves per contact, damping a second stiffness assembly when the
// stiffness-damping coefficient differs between materials.
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "dynamics/obstacles.hpp"
#include "fem/hex_mesh.hpp"

namespace msfab {

enum class ImpactModel {
  kComplementarity,  // nonsmooth Newmark, Kane et al. (Eq. 4.11-4.14 + 4.5)
  kDke,              // + L2 (mass-metric) projection of the contact velocity, §4.4.2
  kBbi,              // + projection in the metric M + h^2/4 K + h/2 D, Eq. 4.19
};
const char* impact_model_name(ImpactModel model);
// "complementarity" | "dke" | "bbi"; InputError naming `field` otherwise.
ImpactModel parse_impact_model(const std::string& name, const std::string& field);

// Coulomb coefficients per (body material name, obstacle surface name), with
// a default for pairs not listed. Never hard-coded: scenes fill it.
struct FrictionTable {
  double default_mu = 0.0;
  std::map<std::pair<std::string, std::string>, double> pairs;
  double mu(const std::string& body_material, const std::string& surface) const {
    const auto it = pairs.find({body_material, surface});
    return it == pairs.end() ? default_mu : it->second;
  }
  // Between two bodies' materials: a pair listed either way round.
  double mu_between(const std::string& a, const std::string& b) const {
    auto it = pairs.find({a, b});
    if (it == pairs.end()) it = pairs.find({b, a});
    return it == pairs.end() ? default_mu : it->second;
  }
};

struct DynamicsModel {
  HexMesh mesh;
  // Per element: density (kg/m^3), Rayleigh mass and stiffness damping a, b
  // (D = a M + b K), and the material name (friction lookup, outputs).
  std::vector<double> density, damping_a, damping_b;
  std::vector<std::string> element_material_name;
  Vec3 gravity = Vec3(0, 0, -9.81);
  // Clamped DOFs (held at their initial positions).
  std::vector<char> fixed;
  bool contact = false;   // obstacles act only when true
  bool friction = false;  // friction acts only when true
  // Vertex-face contact between the mesh's bodies and of a body with itself
  // (B.5), when true; needs `contact`.
  bool body_contact = false;
  std::vector<Obstacle> obstacles;
  FrictionTable friction_table;
  ImpactModel impact = ImpactModel::kBbi;
};

// InputError naming the first inconsistent field (sizes, negative damping,
// non-positive density, mu < 0).
void validate_dynamics_model(const DynamicsModel& model);

}  // namespace msfab
