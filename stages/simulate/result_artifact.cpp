#include "result_artifact.hpp"

#include "core/errors.hpp"
#include "io/artifact.hpp"
#include "io/mesh_io.hpp"
#include "io/xdmf.hpp"

namespace msfab {

std::string write_result_artifact(const std::string& path, const SimulationRecord& r) {
  const HexMesh& mesh = r.mesh->mesh;
  const NewtonResult& nr = *r.newton;
  ArtifactWriter writer(path, kResultSchema, kResultSchemaVersion, "msfab-simulate", r.config_text, r.inputs, r.seed);
  H5File& f = writer.file();
  f.write_attribute("/", "command_line", r.command_line);
  f.write_attribute("/", "scene", r.scene->name);

  f.create_group("/grid");
  f.write_attribute("/grid", "size", std::vector<int>{r.scene->grid.nx, r.scene->grid.ny, r.scene->grid.nz});
  f.write_attribute("/grid", "voxel_size", r.scene->grid.voxel_size);
  write_hex_mesh(f, "/mesh", mesh);

  NodeArray u(mesh.num_nodes(), 3), force(mesh.num_nodes(), 3);
  Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor> fixed(mesh.num_nodes(), 3);
  for (int n = 0; n < mesh.num_nodes(); ++n)
    for (int a = 0; a < 3; ++a) {
      u(n, a) = nr.x[3 * n + a] - mesh.nodes(n, a);
      force(n, a) = r.conditions->force[3 * n + a];
      fixed(n, a) = r.conditions->dirichlet.fixed[3 * n + a];
    }
  H5WriteOptions big;
  big.gzip_level = mesh.num_nodes() > 4096 ? 4 : 0;
  f.write_matrix("/displacement", u, big);
  f.write_attribute("/displacement", "units", "m");
  f.write_matrix("/external_force", force, big);
  f.write_attribute("/external_force", "units", "N");
  f.write_matrix("/fixed", fixed, big);

  std::vector<int> step, iteration;
  std::vector<double> load, residual, energy, alpha, shift;
  for (const auto& h : nr.history) {
    step.push_back(h.load_step);
    iteration.push_back(h.iteration);
    load.push_back(h.load_factor);
    residual.push_back(h.residual);
    energy.push_back(h.energy);
    alpha.push_back(h.step_length);
    shift.push_back(h.shift);
  }
  f.write_vector("/newton/load_step", step);
  f.write_vector("/newton/iteration", iteration);
  f.write_vector("/newton/load_factor", load);
  f.write_vector("/newton/residual", residual);
  f.write_attribute("/newton/residual", "units", "relative to the force scale");
  f.write_vector("/newton/energy", energy);
  f.write_attribute("/newton/energy", "units", "J");
  f.write_vector("/newton/step_length", alpha);
  f.write_vector("/newton/shift", shift);
  std::vector<int> linear_iterations;
  for (const auto& h : nr.history) linear_iterations.push_back(h.linear_iterations);
  f.write_vector("/newton/linear_iterations", linear_iterations);
  f.write_attribute("/newton", "converged", int(nr.converged));
  f.write_attribute("/newton", "iterations", nr.iterations);
  f.write_attribute("/newton", "load_steps", nr.load_steps);

  f.create_group("/timings");
  f.write_attribute("/timings", "units", "s");
  f.write_attribute("/timings", "setup", r.setup_seconds);
  f.write_attribute("/timings", "assembly", nr.timings.assembly);
  f.write_attribute("/timings", "solve", nr.timings.solve);
  f.write_attribute("/timings", "line_search", nr.timings.line_search);
  f.write_attribute("/timings", "newton_total", nr.timings.total);

  f.write_attribute("/", "dofs", mesh.num_dofs());
  f.write_attribute("/", "free_dofs", mesh.num_dofs() - r.conditions->dirichlet.count_fixed());
  f.write_attribute("/", "elements", mesh.num_elements());
  if (r.coarsen_level > 0) {
    f.create_group("/coarsening");
    f.write_attribute("/coarsening", "level", r.coarsen_level);
    f.write_attribute("/coarsening", "material", r.coarse_material);
    f.write_attribute("/coarsening", "element", r.coarse_element);
    if (!r.coarse_fallback.empty()) {
      f.write_attribute("/coarsening", "fallback", r.coarse_fallback);
      f.write_attribute("/coarsening", "fallback_blocks", r.fallback_blocks);
      f.write_attribute("/coarsening", "check_tolerance", r.check_tolerance);
      f.write_attribute("/coarsening", "checked_blocks", r.checked_blocks);
      f.write_attribute("/coarsening", "replaced_blocks", r.replaced_blocks);
    }
    if (r.window > 0) {
      f.write_attribute("/coarsening", "window", r.window);
      f.write_attribute("/coarsening", "unresolved_windows", r.unresolved_windows);
      f.write_attribute("/coarsening", "distinct_windows", r.distinct_windows);
    }
    f.write_attribute("/coarsening", "database", r.database);
    f.write_attribute("/coarsening", "seconds", r.coarsening_seconds);
    f.write_attribute("/coarsening", "fine_elements", r.fine_elements);
    if (r.adaptive) {
      f.write_attribute("/coarsening", "adaptive", 1);
      f.write_attribute("/coarsening", "target_error", r.target_error);
      f.write_attribute("/coarsening", "predicted_error", r.predicted_error);
      f.write_attribute("/coarsening", "a_posteriori_error", r.a_posteriori_error);
      f.write_attribute("/coarsening", "a_posteriori_source", r.a_posteriori_source);
      f.write_attribute("/coarsening", "adaptive_solves", r.adaptive_solves);
      f.write_attribute("/coarsening", "rejected_solve_seconds", r.rejected_solve_seconds);
      f.write_attribute("/coarsening", "uniform_solve_seconds", r.uniform_solve_seconds);
      f.write_attribute("/coarsening", "level_difference", r.level_difference);
      f.write_attribute("/coarsening", "level1_database", r.level1_database);
      f.write_attribute("/coarsening", "elements_per_level",
                        std::vector<int>(r.elements_per_level.begin(), r.elements_per_level.end()));
    }
    if (r.compared) {
      f.write_attribute("/coarsening", "fine_newton_seconds", r.fine_seconds);
      f.write_attribute("/coarsening", "error_vs_fine", r.error_vs_fine);
      f.write_attribute("/coarsening", "error_definition",
                        "mean fine-vertex distance of the trilinearly interpolated coarse displacement to the "
                        "fine one, over the longest rest bounding-box side (thesis 2.5.2)");
      if (r.has_error_floor) {
        f.write_attribute("/coarsening", "error_floor", r.error_floor);
        f.write_attribute("/coarsening", "error_floor_lower_bound", r.error_floor_lower_bound);
        f.write_attribute("/coarsening", "error_floor_definition",
                          "the smallest error_vs_fine of any displacement field on this coarse mesh (the best "
                          "trilinear fit of the fine displacements; no coarse material can do better)");
      }
    }
  }
  writer.commit();

  const std::string xmf = xdmf_sidecar_path(path);
  XdmfHexMesh xm;
  xm.h5_file = file_name_of(path);
  xm.nodes_dataset = "/mesh/nodes";
  xm.connectivity_dataset = "/mesh/elements_vtk";
  xm.n_nodes = mesh.num_nodes();
  xm.n_elems = mesh.num_elements();
  write_hex_mesh_xdmf(xmf, xm,
                      {{"displacement", "/displacement", 3, H5Dtype::kFloat64},
                       {"external_force", "/external_force", 3, H5Dtype::kFloat64}},
                      {{"material_id", "/mesh/element_tag", 1, H5Dtype::kInt32}});
  return xmf;
}

FineReference read_fine_reference(const std::string& path, const VoxelMesh& fine) {
  const ArtifactReader in(path, kResultSchema, kResultSchemaVersion);
  if (in.file().exists("/coarsening")) throw InputError(path + ": --reference must be a fine (uncoarsened) result");
  const MatX u = in.file().read_matrix<double>("/displacement");
  const MatX X = in.file().read_matrix<double>("/mesh/nodes");
  if (u.rows() != fine.mesh.num_nodes() || u.cols() != 3 || X.rows() != u.rows() || X.cols() != 3 ||
      (X - MatX(fine.mesh.nodes)).cwiseAbs().maxCoeff() > 1e-9 * (1.0 + fine.mesh.nodes.cwiseAbs().maxCoeff()))
    throw InputError(path + ": /displacement and /mesh/nodes do not belong to this scene's fine mesh (" +
                     std::to_string(fine.mesh.num_nodes()) + " nodes)");
  FineReference ref;
  ref.displacement.resize(3 * u.rows());
  for (int n = 0; n < u.rows(); ++n)
    for (int a = 0; a < 3; ++a) ref.displacement[3 * n + a] = u(n, a);
  ref.newton_seconds = in.file().read_attribute<double>("/timings", "newton_total");
  return ref;
}

}  // namespace msfab
