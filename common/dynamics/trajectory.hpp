#pragma once
// The record of one dynamics run: per-step samples (energies, centre of
// mass, contacts, cost), full states at output frames, and events. It is
// what `msfab-dynamics` writes as the `msfab.trajectory` artifact
// (docs/artifacts.md) with an XDMF time series for ParaView.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "dynamics/obstacles.hpp"
#include "fem/hex_mesh.hpp"

namespace msfab {

enum class SimulationPhase : int {
  kQuasistatic = 0,  // loading (B.3)
  kElastic = 1,      // Newmark FE dynamics
  kRigid = 2,        // free flight with DMV (B.2)
};
const char* phase_name(SimulationPhase phase);

struct TrajectorySample {
  double time = 0;
  SimulationPhase phase = SimulationPhase::kElastic;
  double kinetic = 0, elastic = 0, gravity = 0;  // J; gravity relative to the rest state
  Vec3 center_of_mass = Vec3::Zero();
  Vec3 com_velocity = Vec3::Zero();
  Vec3 rotation = Vec3::Zero();  // best-fit rotation from rest as a rotation vector (axis * angle, rad)
  // With several bodies: each body's centre of mass (Trajectory::body_names order).
  std::vector<Vec3> body_center_of_mass;
  // Contact candidates at the step's end; contacts carrying a normal
  // impulse at the end of the step or of any of its event substeps.
  int contacts = 0, active_contacts = 0;
  int newton_iterations = 0;
  double max_penetration = 0;  // m
  double seconds = 0;          // wall time of the step
  double total() const { return kinetic + elastic + gravity; }
};

struct TrajectoryFrame {
  double time = 0;
  VecX positions;   // 3N, node-major
  VecX velocities;  // 3N
};

struct TrajectoryEvent {
  double time = 0;
  std::string kind;    // e.g. "contact", "lift-off", "rigid", "elastic", "release", "end"
  std::string detail;  // free text
};

// How the run's mesh was coarsened from the scene's voxel design
// (msfab-dynamics --coarsen; level 0: the fine voxel mesh, nothing stored).
struct TrajectoryCoarsening {
  int level = 0;
  std::string material, database, element, fallback;
  int fallback_blocks = 0;  // ddfem: distinct blocks without a database fit
  // ddfem with --coarse-check: the tolerance (0: off), the solid mixed blocks
  // checked and those replaced by the matched model (cells with a window).
  double check_tolerance = 0;
  int checked_blocks = 0, replaced_blocks = 0;
  // --coarse-window: the margin (0: off) and the cells whose window gave no
  // stiffness (their own C^H was used).
  int window = 0, unresolved_windows = 0;
  int fine_elements = 0;
  double seconds = 0;  // online coarsening time
};

// The run against a fine run of the same scene (msfab-dynamics --reference):
// §2.5.2's error frame by frame (empty reference: no comparison stored).
struct TrajectoryComparison {
  std::string reference;
  double error_at_release = 0, error_max = 0, error_mean = 0, error_final = 0;
  double max_center_of_mass_distance = 0;  // m
  double fine_seconds_per_step = 0, seconds_per_step = 0;
};

struct Trajectory {
  std::string scene;
  NodeArray rest_nodes;                      // rest positions
  std::vector<std::array<int, 8>> elements;  // toolkit node order
  std::vector<int> element_tag;              // material index per element
  std::vector<std::string> material_names;   // tag -> name
  std::vector<std::string> body_names;       // empty or one name per body
  std::vector<TrajectorySample> samples;     // one per step (and the initial state)
  std::vector<TrajectoryFrame> frames;       // at output times
  std::vector<TrajectoryEvent> events;
  // The scene's static obstacles (ground, boxes), so that pictures of the
  // run can show what it jumped onto or over; empty in files written before
  // they were recorded.
  std::vector<Obstacle> obstacles;
  // Wall time by phase (s) and in total.
  double seconds_quasistatic = 0, seconds_elastic = 0, seconds_rigid = 0, seconds_total = 0;
  double time_step = 0;
  int event_substeps = 0;          // the scene's refinement levels around contact events
  std::int64_t elastic_steps = 0;  // Newmark steps taken, substeps counted one each
  std::string impact_model;
  TrajectoryCoarsening coarsening;
  TrajectoryComparison comparison;
};

struct TrajectoryProvenance {
  std::string executable = "msfab-dynamics";
  std::string config_text;
  std::vector<std::string> inputs;  // artifact paths used (e.g. a dac_model)
  std::uint64_t seed = 0;
};

// Writes the artifact atomically and its XDMF sidecar (one grid per frame
// with displacement and velocity fields); returns the sidecar's path.
std::string write_trajectory_artifact(const std::string& path, const Trajectory& trajectory,
                                      const TrajectoryProvenance& provenance);

// Reads what write_trajectory_artifact wrote (InputError naming the file and
// field on anything missing or inconsistent).
Trajectory read_trajectory_artifact(const std::string& path);

}  // namespace msfab
