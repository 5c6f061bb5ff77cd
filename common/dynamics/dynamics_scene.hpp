#pragma once
// A dynamics scene read from YAML (configs/dynamics/*.yaml, documented in
// docs/dynamics.md): materials with their identified parameters, voxel
// geometry painted from boxes, placement and initial velocity, clamps,
// obstacles and friction, an optional preload (a static pluck or a
// quasistatic press against the obstacles) that is released at t = 0, and
// the integration settings.
#include <memory>
#include <string>
#include <vector>

#include "ddfem/voxel_coarsening.hpp"
#include "dynamics/dynamics_model.hpp"
#include "dynamics/newmark_integrator.hpp"
#include "fem/voxel_grid.hpp"
#include "io/config.hpp"

namespace msfab {

struct DynamicsCoarsening;

struct SceneMaterial {
  std::string name;
  double E = 0, nu = 0, density = 0, damping_a = 0, damping_b = 0;
};

// Nodes whose initial position lies in [lo, hi] get a force; the total is
// spread equally over them.
struct RegionLoad {
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
  Vec3 force = Vec3::Zero();
};

// kDynamicPress is B.3's reference for the quasistatic press: the press
// load is not a preload but acts during the run, ramped from zero to full
// over `press_ramp_time` and then held (`press.mode: dynamic`).
enum class Preload { kNone, kStaticPluck, kQuasistaticPress, kDynamicPress };

struct RigidFlightSettings {
  bool enabled = false;
  // Switch to the rigid model when the elastic energy is below this fraction
  // of the kinetic energy and no contact is within `lookahead_steps` steps.
  double elastic_fraction = 1e-3;
  int lookahead_steps = 10;
};

struct DynamicsScene {
  std::string name;
  std::vector<SceneMaterial> materials;
  VoxelGrid grid;  // material ids = index in `materials` + 1
  // Bodies: geometry boxes name theirs (`body:`); elements of different
  // bodies share no node and meet only through contact.
  std::vector<std::string> body_names;
  std::vector<int> element_body;
  std::vector<std::string> geometry_files;  // voxel arrays and surface meshes the layout read
  DynamicsModel model;
  VecX initial_positions, initial_velocities;
  NewmarkOptions newmark;
  // Elastic steps in which a contact event falls (the active contacts start
  // or stop) or that fail are retaken as two halves, recursively, down to
  // time_step / 2^event_substeps (`simulation.event_substeps`; 0: never).
  int event_substeps = 0;
  double duration = 0;
  int output_every = 1;
  Preload preload = Preload::kNone;
  RegionLoad load;
  int preload_steps = 4;
  // Press only: when the full load would fold the body through itself (the
  // press solver without self-contact), stop at the largest load that does
  // not, i.e. when the pressed part touches the part below it, instead of
  // refusing the scene (`press.stop_at_touch`).
  bool stop_at_touch = false;
  // Press only: the quasistatic press with self-contact (parts that touch
  // are tied without slip and carry the load on; `press.self_contact`).
  bool press_self_contact = false;
  double press_ramp_time = 0;  // kDynamicPress: seconds from zero to the full load
  RigidFlightSettings rigid;
  // Set when the design was coarsened (DDFEM or a baseline): `grid` stays
  // the fine design, `model.mesh` is the coarse mesh (dynamics/coarse_dynamics.hpp).
  std::shared_ptr<const DynamicsCoarsening> coarsening;
};

// The constitutive models of a scene's materials by voxel id ([0] = void).
std::vector<MaterialPtr> scene_palette(const std::vector<SceneMaterial>& materials);

// Reads and validates everything (InputError naming file, key and problem);
// the caller runs check_no_unknown_keys() afterwards. A request of level 1
// or 2 simulates the design on coarse elements (one body, no geometry
// parameters, trilinear element; dynamics/coarse_dynamics.hpp).
DynamicsScene read_dynamics_scene(const Config& config, const CoarseningRequest& coarsening = {});

// The nodal force vector of a region load on the initial positions
// (InputError if the region holds no node).
VecX region_force(const DynamicsScene& scene, const RegionLoad& load, const std::string& what);

}  // namespace msfab
