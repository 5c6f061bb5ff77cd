#pragma once
// DDFEM in dynamics (thesis §2.5.2: the coarsening is "equally applicable"
// to dynamic simulation). A dynamics scene's voxel design is coarsened as a
// static scene's is (ddfem/voxel_coarsening.hpp) and the coarse mesh
// replaces the fine one in the Newmark integrator; what dynamics adds per
// coarse element is its inertia and damping:
//   density    rho_e = sum_c rho_c / 8^level       (children c, void 0: the block's mass is kept)
//   mass damping      a_e = sum_c rho_c a_c / sum_c rho_c   (D = a M: the damping of the mass is kept)
//   stiffness damping b_e = sum_c E_c b_c / sum_c E_c       (D = b K: weighted as the stiffness is)
//   material   the child material of largest volume (friction lookups, outputs)
// A run is then compared with the fine run of the same scene frame by frame
// with §2.5.2's error: coarse displacements interpolated trilinearly to the
// fine nodes, mean distance over the longest side of the rest box.
#include <memory>
#include <string>
#include <vector>

#include "ddfem/voxel_coarsening.hpp"
#include "dynamics/dynamics_model.hpp"
#include "dynamics/dynamics_scene.hpp"
#include "dynamics/trajectory.hpp"

namespace msfab {

struct CoarseElementInertia {
  std::vector<double> density, damping_a, damping_b;
  std::vector<int> material_id;  // voxel id (index in the scene's materials + 1)
};

// Per element of `coarse.mesh`, from the fine voxels each covers.
// `materials[id - 1]` describes voxel id `id`.
CoarseElementInertia coarse_element_inertia(const VoxelGrid& fine, const CoarsenedVoxels& coarse,
                                            const std::vector<SceneMaterial>& materials);

// The coarsened scene's bookkeeping: the fine voxel mesh it stands for, in
// its initial placement, and the trilinear interpolation from the coarse
// nodes to the fine ones. Region loads are applied to the fine nodes and
// restricted by P^T (total force and moment kept, as in the static
// coarsening); the comparison with a fine run interpolates by P.
struct DynamicsCoarsening {
  CoarseningRequest request;
  CoarsenedVoxels coarse;
  VoxelMesh fine;
  VecX fine_initial_positions;  // 3 per fine node
  SpMat to_fine;                // P: (fine nodes) x (coarse nodes)
};

// The design `grid` (voxel id i: materials[i - 1], palette[i]) coarsened as
// `request` says: sets model.mesh (element_tag: the material id of the
// largest share), density, damping and material names. The fine positions
// are left for the caller, who knows the placement. InputError for a bad
// request or an enhanced element.
std::shared_ptr<DynamicsCoarsening> coarsen_dynamics_design(const VoxelGrid& grid,
                                                            const std::vector<SceneMaterial>& materials,
                                                            const std::vector<MaterialPtr>& palette,
                                                            const CoarseningRequest& request, DynamicsModel& model);

struct TrajectoryDifference {
  std::vector<double> time, error;  // per output frame: §2.5.2's error of the model against the fine run
  double max_error = 0, final_error = 0, mean_error = 0;
  double max_center_of_mass_distance = 0;  // m, over the steps both runs sampled
  // Newmark cost: wall seconds per elastic step.
  double fine_seconds_per_step = 0, model_seconds_per_step = 0;
  int fine_steps = 0, model_steps = 0;
  int fine_nodes = 0, model_nodes = 0;
};

// InputError naming `fine_path` unless `fine` is a run of `scene` on its fine
// mesh (rest nodes equal: the voxel mesh the coarsening stands for, or the
// scene's own mesh) with at least one output frame and the scene's time
// step; cheap, so a stage checks before it runs.
void check_fine_reference(const DynamicsScene& scene, const Trajectory& fine, const std::string& fine_path);

// `model` is the run of `scene` (coarsened or not); `fine` the run of the
// same scene on the fine mesh, read from `fine_path`. InputError naming
// `fine_path` when it is not that: other rest nodes, time step or frame
// times, a run without frames.
TrajectoryDifference compare_with_fine(const DynamicsScene& scene, const Trajectory& model, const Trajectory& fine,
                                       const std::string& fine_path);

// What the trajectory artifact records of a coarsening and of a comparison.
TrajectoryCoarsening coarsening_record(const DynamicsCoarsening& coarsening);
TrajectoryComparison comparison_record(const TrajectoryDifference& difference, const std::string& fine_path);

}  // namespace msfab
