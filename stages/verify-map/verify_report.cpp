#include "verify_report.hpp"

#include "io/artifact.hpp"

namespace msfab {

void write_verify_report(const std::string& path, const VerifyReport& r, const std::string& executable,
                         const std::string& config_text, const std::vector<std::string>& inputs, std::uint64_t seed) {
  ArtifactWriter out(path, kVerifyMapSchema, kVerifyMapSchemaVersion, executable, config_text, inputs, seed);
  H5File& f = out.file();
  f.write_attribute("/", "fill", r.fill);
  f.write_attribute("/", "tile_structure", static_cast<std::int32_t>(r.tile_structure));
  f.write_attribute("/", "grid", std::vector<std::int32_t>{r.grid[0], r.grid[1], r.grid[2]});
  f.write_attribute("/", "cell_size", r.cell_size);
  f.write_attribute("/", "cell_voxels", static_cast<std::int32_t>(r.resolution));
  f.write_attribute("/", "tiling", static_cast<std::int32_t>(r.tiling));
  f.write_attribute(
      "/", "voxel_grid",
      std::vector<std::int64_t>{std::int64_t(r.grid[0]) * r.resolution, std::int64_t(r.grid[1]) * r.resolution,
                                std::int64_t(r.grid[2]) * r.resolution});
  f.write_attribute("/", "voxels", r.voxels);
  f.write_attribute("/", "material_voxels", r.material_voxels);
  f.write_attribute("/", "void_ratio", r.void_ratio);
  f.write_attribute("/", "void", r.void_model);
  f.write_attribute("/", "pieces_full", r.pieces_full);
  f.write_attribute("/", "removed_pieces_full", r.removed_pieces_full);
  f.write_attribute("/", "removed_voxels_full", r.removed_voxels_full);
  f.write_attribute("/", "inactive_nodes_full", r.inactive_nodes_full);
  f.write_attribute("/", "pieces_homogenized", r.pieces_homogenized);
  f.write_attribute("/", "removed_pieces_homogenized", r.removed_pieces_homogenized);
  f.write_attribute("/", "removed_cells_homogenized", r.removed_cells_homogenized);
  f.write_attribute("/", "inactive_nodes_homogenized", r.inactive_nodes_homogenized);
  f.write_attribute("/", "homogenized_elements", static_cast<std::int32_t>(r.homogenized_elements));
  f.write_attribute("/", "solver_homogenized", r.solver_homogenized);
  f.write_attribute("/", "solver_full", r.solver_full);
  f.write_attribute("/", "coarse_space_full", r.coarse_space_full);
  f.write_attribute("/", "unknowns_homogenized", r.unknowns_homogenized);
  f.write_attribute("/", "unknowns_full", r.unknowns_full);
  f.write_attribute("/", "point_supports", r.point_supports);
  f.write_attribute("/", "moved_point_supports", r.moved_point_supports);
  f.write_attribute("/", "lost_point_supports", r.lost_point_supports);
  f.write_attribute("/", "edge_joints", r.edge_joints);
  f.write_attribute("/", "edge_joint_largest_ratio", r.edge_joint_largest_ratio);

  f.create_group("/timings");
  f.write_attribute("/timings", "model", r.seconds_model);
  f.write_attribute("/timings", "factorize_homogenized", r.seconds_factorize_homogenized);
  f.write_attribute("/timings", "factorize_full", r.seconds_factorize_full);
  f.write_attribute("/timings", "total", r.seconds_total);
  f.write_attribute("/timings", "units", "s");

  std::vector<std::string> names;
  std::vector<double> mean_hom, mean_full, mean_diff, rel_disp, e_hom, e_full, rel_e, t_hom, t_full;
  std::vector<std::int64_t> compared, nearest, iterations, point_loads, fallbacks, loaded;
  const std::size_t n_cases = r.cases.size();
  const Eigen::Index nodes = n_cases ? r.cases[0].homogenized.rows() : 0;
  std::vector<double> u_hom(n_cases * std::size_t(nodes) * 3), u_full(u_hom.size());
  for (std::size_t k = 0; k < n_cases; ++k) {
    const VerifyCase& c = r.cases[k];
    names.push_back(c.name);
    mean_hom.push_back(c.displacement.mean_homogenized);
    mean_full.push_back(c.displacement.mean_full);
    mean_diff.push_back(c.displacement.mean_difference);
    rel_disp.push_back(c.displacement.relative);
    e_hom.push_back(c.energy_homogenized);
    e_full.push_back(c.energy_full);
    rel_e.push_back(c.relative_energy);
    t_hom.push_back(c.solve_seconds_homogenized);
    t_full.push_back(c.solve_seconds_full);
    compared.push_back(c.displacement.compared);
    nearest.push_back(c.displacement.nearest);
    iterations.push_back(c.iterations_full);
    point_loads.push_back(c.point_loads);
    fallbacks.push_back(c.load_fallbacks);
    loaded.push_back(c.loaded_fine_nodes);
    for (Eigen::Index n = 0; n < nodes; ++n)
      for (int a = 0; a < 3; ++a) {
        const std::size_t i = (k * std::size_t(nodes) + std::size_t(n)) * 3 + std::size_t(a);
        u_hom[i] = c.homogenized(n, a);
        u_full[i] = c.displacement.sampled(n, a);
      }
  }
  f.create_group("/cases");
  f.write_attribute("/cases", "names", format_name_list(names));
  f.write_vector("/cases/mean_displacement_homogenized", mean_hom);
  f.write_vector("/cases/mean_displacement_full", mean_full);
  f.write_vector("/cases/mean_displacement_difference", mean_diff);
  f.write_vector("/cases/relative_displacement_difference", rel_disp);
  f.write_vector("/cases/energy_homogenized", e_hom);
  f.write_vector("/cases/energy_full", e_full);
  f.write_vector("/cases/relative_energy_difference", rel_e);
  f.write_vector("/cases/solve_seconds_homogenized", t_hom);
  f.write_vector("/cases/solve_seconds_full", t_full);
  f.write_vector("/cases/compared_nodes", compared);
  f.write_vector("/cases/nearest_samples", nearest);
  f.write_vector("/cases/cg_iterations_full", iterations);
  f.write_vector("/cases/point_loads", point_loads);
  f.write_vector("/cases/load_fallbacks", fallbacks);
  f.write_vector("/cases/loaded_fine_nodes", loaded);
  for (const char* d :
       {"/cases/mean_displacement_homogenized", "/cases/mean_displacement_full", "/cases/mean_displacement_difference"})
    f.write_attribute(d, "units", "m");
  for (const char* d : {"/cases/energy_homogenized", "/cases/energy_full"}) f.write_attribute(d, "units", "J");

  const std::vector<hsize_t> shape{hsize_t(n_cases), hsize_t(nodes), 3};
  f.write_dataset("/nodes/displacement_homogenized", u_hom, shape);
  f.write_dataset("/nodes/displacement_full", u_full, shape);
  f.write_attribute("/nodes/displacement_homogenized", "units", "m");
  f.write_attribute("/nodes/displacement_full", "units", "m");
  std::vector<std::uint8_t> kind;
  if (n_cases)
    for (SampleKind s : r.cases[0].displacement.kind) kind.push_back(static_cast<std::uint8_t>(s));
  f.write_vector("/nodes/sample_kind", kind);
  out.commit();
}

}  // namespace msfab
