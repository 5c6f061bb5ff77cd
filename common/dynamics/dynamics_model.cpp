#include "dynamics/dynamics_model.hpp"

#include <cmath>

#include "core/errors.hpp"

namespace msfab {

const char* impact_model_name(ImpactModel model) {
  switch (model) {
    case ImpactModel::kComplementarity: return "complementarity";
    case ImpactModel::kDke: return "dke";
    case ImpactModel::kBbi: return "bbi";
  }
  return "?";
}

ImpactModel parse_impact_model(const std::string& name, const std::string& field) {
  if (name == "complementarity") return ImpactModel::kComplementarity;
  if (name == "dke") return ImpactModel::kDke;
  if (name == "bbi") return ImpactModel::kBbi;
  throw InputError(field + ": unknown impact model '" + name + "' (complementarity, dke or bbi)");
}

void validate_dynamics_model(const DynamicsModel& m) {
  const size_t ne = static_cast<size_t>(m.mesh.num_elements());
  if (ne == 0) throw InputError("dynamics model: the mesh has no elements");
  if (m.density.size() != ne || m.damping_a.size() != ne || m.damping_b.size() != ne ||
      m.element_material_name.size() != ne)
    throw InputError("dynamics model: per-element density/damping/material arrays do not match the element count");
  for (size_t e = 0; e < ne; ++e) {
    if (!(m.density[e] > 0) || !std::isfinite(m.density[e]))
      throw InputError("dynamics model: material '" + m.element_material_name[e] + "' density must be positive");
    if (!(m.damping_a[e] >= 0) || !(m.damping_b[e] >= 0) || !std::isfinite(m.damping_a[e]) ||
        !std::isfinite(m.damping_b[e]))
      throw InputError("dynamics model: material '" + m.element_material_name[e] +
                       "' Rayleigh damping a, b must be finite and >= 0");
  }
  if (!m.fixed.empty() && m.fixed.size() != static_cast<size_t>(m.mesh.num_dofs()))
    throw InputError("dynamics model: fixed-DOF mask has the wrong size");
  if (!m.gravity.allFinite()) throw InputError("dynamics model: gravity must be finite");
  if (!(m.friction_table.default_mu >= 0) || !std::isfinite(m.friction_table.default_mu))
    throw InputError("dynamics model: friction coefficient must be >= 0 (got " +
                     std::to_string(m.friction_table.default_mu) + ")");
  for (const auto& [pair, mu] : m.friction_table.pairs)
    if (!(mu >= 0) || !std::isfinite(mu))
      throw InputError("dynamics model: friction coefficient for (" + pair.first + ", " + pair.second +
                       ") must be >= 0 (got " + std::to_string(mu) + ")");
}

}  // namespace msfab
