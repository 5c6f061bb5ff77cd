#pragma once
// A topology-optimization scene from its YAML config (docs/topopt.md):
// grid, design domain, supports, load cases, targets, mass terms and the
// material space. Boxes are in physical coordinates (a node at grid index
// (i, j, k) sits at (i, j, k) h); a node belongs to a box when it lies in
// it up to 1e-9 h, a cell when its centre does. Every problem a scene can
// have is an InputError naming the config key: no support, a load or a
// target that selects no node, a load on a node that only empty cells
// touch, a prescribed value on a node no support fixes.
#include <string>
#include <vector>

#include "io/config.hpp"
#include "topopt/topology_objective.hpp"

namespace msfab {

struct TopoptScene {
  TopologySetup setup;
  std::string space;
  double E0 = 1.0, nu = 0.3, penalty = 3.0, E_min_ratio = 1e-9, decades = 4.0;
  double volume_fraction = 0;  // > 0: a hard mass budget volume_fraction * domain volume
  // `elements_per_cell`: hexahedra per design cell edge for the elasticity
  // (3D). The setup above is on the design grid; the stage refines it
  // (TopologySetup::fem_grid).
  int elements_per_cell = 1;
};

// Reads grid, domain, supports, loads, mass, filter, solver and the
// material keys. `E_stiff` (from the gamut artifact, or 0) overrides
// material.E for gamut spaces.
TopoptScene read_topopt_scene(const Config& config, double gamut_E_stiff, double gamut_decades);

}  // namespace msfab
