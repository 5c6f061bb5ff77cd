#include "dynamics/coarse_dynamics.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/errors.hpp"
#include "ddfem/coarsening_error.hpp"

namespace msfab {

namespace {

using NodeRowsMap = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;

VecX displacement_from_rest(const VecX& positions, const NodeArray& rest) {
  VecX u = positions;
  for (int n = 0; n < rest.rows(); ++n) u.segment<3>(3 * n) -= rest.row(n).transpose();
  return u;
}

void seconds_per_elastic_step(const Trajectory& t, double& seconds, int& steps) {
  double total = 0;
  steps = 0;
  for (const TrajectorySample& s : t.samples)
    if (s.phase == SimulationPhase::kElastic && s.time > 0) total += s.seconds, ++steps;
  seconds = steps ? total / steps : 0.0;
}

// The mesh a fine run of the scene has: the voxel mesh a coarsening stands
// for, or the scene's own.
const HexMesh& fine_mesh_of(const DynamicsScene& scene) {
  return scene.coarsening ? scene.coarsening->fine.mesh : scene.model.mesh;
}

}  // namespace

std::shared_ptr<DynamicsCoarsening> coarsen_dynamics_design(const VoxelGrid& grid,
                                                            const std::vector<SceneMaterial>& materials,
                                                            const std::vector<MaterialPtr>& palette,
                                                            const CoarseningRequest& request, DynamicsModel& model) {
  if (request.element == "enhanced")
    throw InputError("--coarse-element enhanced: dynamics runs trilinear coarse elements only");
  auto state = std::make_shared<DynamicsCoarsening>();
  state->request = request;
  state->coarse = coarsen_voxels(grid, palette, request);
  if (state->coarse.element != "trilinear")
    throw InputError(request.database + ": fitted for the " + state->coarse.element +
                     " element; dynamics runs trilinear coarse elements only");
  state->fine = build_voxel_mesh(grid, palette);
  state->to_fine = coarse_to_fine_interpolation(grid, state->fine, state->coarse.grid, state->coarse.mesh);
  const CoarseElementInertia inertia = coarse_element_inertia(grid, state->coarse, materials);
  model.mesh = state->coarse.mesh.mesh;
  model.density = inertia.density;
  model.damping_a = inertia.damping_a;
  model.damping_b = inertia.damping_b;
  model.mesh.element_tag = inertia.material_id;
  model.element_material_name.clear();
  for (int id : inertia.material_id) model.element_material_name.push_back(materials[id - 1].name);
  return state;
}

void check_fine_reference(const DynamicsScene& scene, const Trajectory& fine, const std::string& fine_path) {
  const HexMesh& fine_mesh = fine_mesh_of(scene);
  const int nf = fine_mesh.num_nodes();
  if (fine.rest_nodes.rows() != nf)
    throw InputError(fine_path + ": the reference has " + std::to_string(fine.rest_nodes.rows()) +
                     " rest nodes; the fine mesh of this scene has " + std::to_string(nf) +
                     " (not a fine run of this scene)");
  if ((fine.rest_nodes - fine_mesh.nodes).cwiseAbs().maxCoeff() > 1e-9 * scene.grid.voxel_size)
    throw InputError(fine_path +
                     ": dataset '/mesh/nodes' differs from this scene's fine mesh (not a fine run of "
                     "this scene, or one with other scene parameters)");
  if (fine.frames.empty()) throw InputError(fine_path + ": holds no output frame");
  const double time_step = scene.newmark.time_step;
  if (std::abs(fine.time_step - time_step) > 1e-9 * time_step) {
    std::ostringstream msg;
    msg << fine_path << ": run with time step " << fine.time_step << " s, this scene's is " << time_step
        << " s (the frames must fall at the same times)";
    throw InputError(msg.str());
  }
}

CoarseElementInertia coarse_element_inertia(const VoxelGrid& fine, const CoarsenedVoxels& coarse,
                                            const std::vector<SceneMaterial>& materials) {
  const CoarseGrid& g = coarse.grid;
  const int f = g.fine_per_cell();
  const int ne = coarse.mesh.mesh.num_elements();
  CoarseElementInertia out;
  out.density.resize(ne);
  out.damping_a.resize(ne);
  out.damping_b.resize(ne);
  out.material_id.resize(ne);
  std::vector<int> count(materials.size() + 1);
  for (int e = 0; e < ne; ++e) {
    const int cell = coarse.mesh.element_voxel[e];
    const int ci = cell % g.nx, cj = (cell / g.nx) % g.ny, ck = cell / (g.nx * g.ny);
    std::fill(count.begin(), count.end(), 0);
    // Children beyond the fine grid (odd sizes, padded) are void.
    for (int k = ck * f; k < std::min((ck + 1) * f, fine.nz); ++k)
      for (int j = cj * f; j < std::min((cj + 1) * f, fine.ny); ++j)
        for (int i = ci * f; i < std::min((ci + 1) * f, fine.nx); ++i) ++count[fine.at(i, j, k)];
    double mass = 0, mass_a = 0, stiffness = 0, stiffness_b = 0;
    int best = 0;
    for (size_t id = 1; id < count.size(); ++id) {
      if (!count[id]) continue;
      const SceneMaterial& m = materials[id - 1];
      mass += count[id] * m.density;
      mass_a += count[id] * m.density * m.damping_a;
      stiffness += count[id] * m.E;
      stiffness_b += count[id] * m.E * m.damping_b;
      if (!best || count[id] > count[best]) best = static_cast<int>(id);
    }
    if (!best) throw std::logic_error("coarse_element_inertia: an element of the coarse mesh covers no solid voxel");
    out.density[e] = mass / double(f * f * f);
    out.damping_a[e] = mass_a / mass;
    out.damping_b[e] = stiffness_b / stiffness;
    out.material_id[e] = best;
  }
  return out;
}

TrajectoryDifference compare_with_fine(const DynamicsScene& scene, const Trajectory& model, const Trajectory& fine,
                                       const std::string& fine_path) {
  check_fine_reference(scene, fine, fine_path);
  const HexMesh& fine_mesh = fine_mesh_of(scene);
  const int nf = fine_mesh.num_nodes();
  if (model.frames.empty()) throw InputError("this run: holds no output frame");
  if (fine.frames.size() != model.frames.size())
    throw InputError(fine_path + ": the reference has " + std::to_string(fine.frames.size()) + " frames, this run " +
                     std::to_string(model.frames.size()) +
                     " (simulation.time_step, duration and output_every must "
                     "be the same)");
  const double step = std::max(fine.time_step, model.time_step);
  for (size_t i = 0; i < fine.frames.size(); ++i)
    if (std::abs(fine.frames[i].time - model.frames[i].time) > 1e-6 * step) {
      std::ostringstream msg;
      msg << fine_path << ": frame " << i << " is at t = " << fine.frames[i].time << " s, this run's at "
          << model.frames[i].time << " s (simulation.time_step and output_every must be the same)";
      throw InputError(msg.str());
    }

  const SpMat* P = scene.coarsening ? &scene.coarsening->to_fine : nullptr;
  if ((P ? P->cols() : nf) != model.rest_nodes.rows())
    throw std::logic_error("compare_with_fine: the run's mesh is not the model it was compared as");

  TrajectoryDifference d;
  d.fine_nodes = nf;
  d.model_nodes = static_cast<int>(model.rest_nodes.rows());
  for (size_t i = 0; i < fine.frames.size(); ++i) {
    const VecX uf = displacement_from_rest(fine.frames[i].positions, fine.rest_nodes);
    const VecX um = displacement_from_rest(model.frames[i].positions, model.rest_nodes);
    VecX interpolated = um;
    if (P) {
      interpolated.resize(3 * nf);
      Eigen::Map<NodeRowsMap>(interpolated.data(), nf, 3) =
          *P * Eigen::Map<const NodeRowsMap>(um.data(), d.model_nodes, 3);
    }
    const double e = mean_vertex_error(fine_mesh, uf, interpolated);
    d.time.push_back(fine.frames[i].time);
    d.error.push_back(e);
    d.max_error = std::max(d.max_error, e);
    d.mean_error += e / double(fine.frames.size());
  }
  d.final_error = d.error.back();
  const size_t samples = std::min(fine.samples.size(), model.samples.size());
  for (size_t i = 0; i < samples; ++i)
    if (std::abs(fine.samples[i].time - model.samples[i].time) <= 1e-6 * step)
      d.max_center_of_mass_distance = std::max(
          d.max_center_of_mass_distance, (fine.samples[i].center_of_mass - model.samples[i].center_of_mass).norm());
  seconds_per_elastic_step(fine, d.fine_seconds_per_step, d.fine_steps);
  seconds_per_elastic_step(model, d.model_seconds_per_step, d.model_steps);
  return d;
}

TrajectoryCoarsening coarsening_record(const DynamicsCoarsening& coarsening) {
  const CoarsenedVoxels& c = coarsening.coarse;
  TrajectoryCoarsening r;
  r.level = coarsening.request.level;
  r.material = coarsening.request.material;
  r.database = coarsening.request.database;
  r.element = c.element;
  r.fallback = r.material == "ddfem" ? c.fallback : std::string();
  r.fallback_blocks = c.fallback_blocks;
  r.check_tolerance = c.check_tolerance;
  r.checked_blocks = c.checked_blocks;
  r.replaced_blocks = c.replaced_blocks;
  r.window = coarsening.request.window;
  r.unresolved_windows = c.unresolved_windows;
  r.fine_elements = coarsening.fine.mesh.num_elements();
  r.seconds = c.seconds;
  return r;
}

TrajectoryComparison comparison_record(const TrajectoryDifference& d, const std::string& fine_path) {
  TrajectoryComparison r;
  r.reference = fine_path;
  r.error_at_release = d.error.empty() ? 0.0 : d.error.front();
  r.error_max = d.max_error;
  r.error_mean = d.mean_error;
  r.error_final = d.final_error;
  r.max_center_of_mass_distance = d.max_center_of_mass_distance;
  r.fine_seconds_per_step = d.fine_seconds_per_step;
  r.seconds_per_step = d.model_seconds_per_step;
  return r;
}

}  // namespace msfab
