// msfab-dynamics: transient dynamics of a dynamics scene (thesis ch. 4,
// App. B), phase by phase:
//
//   1. read the scene: materials with identified E_n and Rayleigh damping,
//      voxel geometry, placement, clamps, obstacles, friction, preload;
//      with --coarsen, the design coarsened by DDFEM lookups (§2.5.2)
//   2. preload: a static pluck or a quasistatic press with no-slip contact
//      (B.3), released at t = 0
//   3. implicit Newmark steps (Eq. 4.2-4.6) with frictional contact
//      (4.11-4.14, B.13-B.19) and the scene's impact model: complementarity,
//      DKE or BBI (4.19, B.20-B.21)
//   4. with rigid flight enabled: rigid projection (B.22), DMV free flight,
//      projection back before the next contact (B.23)
//   5. write the `msfab.trajectory` artifact and its ParaView time series
//      (`python3 -m msfab report` draws its energies and centre of mass); with
//      --reference, the run's difference from the fine run frame by frame
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "cli/progress.hpp"
#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "ddfem/coarsening_options.hpp"
#include "default_scene.hpp"
#include "dynamics/coarse_dynamics.hpp"
#include "dynamics/dynamics_run.hpp"
#include "dynamics/dynamics_scene.hpp"
#include "dynamics/trajectory.hpp"
#include "io/atomic_file.hpp"

using namespace msfab;

namespace {

struct MarkerTrace {
  int node = -1;
  std::vector<double> time;
  std::vector<Vec3> position;
  void add(double t, const VecX& q) {
    time.push_back(t);
    position.push_back(q.segment<3>(3 * node));
  }
};

int nearest_rest_node(const DynamicsScene& scene, const Vec3& x) {
  int best = 0;
  for (int i = 1; i < scene.model.mesh.num_nodes(); ++i)
    if ((scene.model.mesh.nodes.row(i).transpose() - x).norm() <
        (scene.model.mesh.nodes.row(best).transpose() - x).norm())
      best = i;
  return best;
}

// Written atomically (io/atomic_file.hpp), so an existing file survives a failure.
void write_marker_csv(const std::string& path, const MarkerTrace& trace) {
  std::string text = "t,x,y,z\n";
  char line[128];
  for (size_t i = 0; i < trace.time.size(); ++i) {
    std::snprintf(line, sizeof line, "%.10g,%.12g,%.12g,%.12g\n", trace.time[i], trace.position[i].x(),
                  trace.position[i].y(), trace.position[i].z());
    text += line;
  }
  write_file_atomically(path, text);
}

void print_summary(const DynamicsScene& scene, const Trajectory& t) {
  int elastic_steps = 0, rigid_steps = 0, newton = 0, max_contacts = 0;
  double max_penetration = 0, max_z = -INFINITY, step_seconds = 0;
  for (const TrajectorySample& s : t.samples) {
    if (s.phase == SimulationPhase::kElastic && s.time > 0)
      ++elastic_steps, newton += s.newton_iterations, step_seconds += s.seconds;
    if (s.phase == SimulationPhase::kRigid) ++rigid_steps;
    max_contacts = std::max(max_contacts, s.active_contacts);
    max_penetration = std::max(max_penetration, s.max_penetration);
    max_z = std::max(max_z, s.center_of_mass.z());
  }
  const TrajectorySample& first = t.samples.front();
  const TrajectorySample& last = t.samples.back();
  std::printf("msfab-dynamics: scene '%s', %d elements, %d DOFs, impact model %s, h = %g s\n", scene.name.c_str(),
              scene.model.mesh.num_elements(), scene.model.mesh.num_dofs(), t.impact_model.c_str(), t.time_step);
  std::printf("  %d elastic steps (%.2f Newton iterations, %.3f ms each), %d rigid steps\n", elastic_steps,
              elastic_steps ? double(newton) / elastic_steps : 0.0,
              elastic_steps ? 1e3 * step_seconds / elastic_steps : 0.0, rigid_steps);
  if (t.event_substeps > 0)
    std::printf("  event substeps (down to h / %d): %lld Newmark steps for the %d elastic steps\n",
                1 << t.event_substeps, static_cast<long long>(t.elastic_steps), elastic_steps);
  std::printf("  centre of mass: start (%.5f, %.5f, %.5f) m, end (%.5f, %.5f, %.5f) m, highest z %.5f m\n",
              first.center_of_mass.x(), first.center_of_mass.y(), first.center_of_mass.z(), last.center_of_mass.x(),
              last.center_of_mass.y(), last.center_of_mass.z(), max_z);
  std::printf("  rotation at the end: %.2f deg; energy start %.4e J, end %.4e J\n", last.rotation.norm() * 180 / M_PI,
              first.total(), last.total());
  std::printf("  contacts: up to %d active nodes, deepest penetration %.3e m\n", max_contacts, max_penetration);
  // Rebound: how far the centre of mass rises after the first contact above
  // its height at that contact.
  const TrajectorySample* contact = nullptr;
  double after_contact = -INFINITY;
  for (const TrajectorySample& s : t.samples) {
    if (!contact && s.active_contacts > 0) contact = &s;
    if (contact) after_contact = std::max(after_contact, s.center_of_mass.z());
  }
  if (contact)
    std::printf("  rebound after the first contact: %.4e m (centre of mass at contact %.5f m, highest after %.5f m)\n",
                after_contact - contact->center_of_mass.z(), contact->center_of_mass.z(), after_contact);
  // Each body of a multi-body scene: where it starts, how high it gets and
  // where it ends (a thrown projectile's landing spot once it has settled).
  for (size_t b = 0; b < t.body_names.size(); ++b) {
    double top = -INFINITY;
    for (const TrajectorySample& s : t.samples) top = std::max(top, s.body_center_of_mass[b].z());
    const Vec3 a = first.body_center_of_mass[b], e = last.body_center_of_mass[b];
    std::printf("  body %-10s centre of mass start (%.5f, %.5f, %.5f) m, end (%.5f, %.5f, %.5f) m, highest z %.5f m\n",
                t.body_names[b].c_str(), a.x(), a.y(), a.z(), e.x(), e.y(), e.z(), top);
  }
  for (const TrajectoryEvent& e : t.events)
    std::printf("  event %-9s t = %.5f s  %s\n", e.kind.c_str(), e.time, e.detail.c_str());
  std::printf("  time: preload %.3f s, elastic %.3f s, rigid %.3f s, total %.3f s\n", t.seconds_quasistatic,
              t.seconds_elastic, t.seconds_rigid, t.seconds_total);
}

void print_difference(const TrajectoryDifference& d) {
  std::printf(
      "  vs fine (%s): error at release %.3e, max %.3e, mean %.3e, at the end %.3e over %zu frames\n"
      "    (mean fine-vertex distance of this run's displacements interpolated to the fine nodes, over the\n"
      "     longest side of the rest box; thesis 2.5.2); centre of mass apart by up to %.3e m\n",
      d.model_nodes == d.fine_nodes ? "same mesh" : "interpolated", d.error.front(), d.max_error, d.mean_error,
      d.final_error, d.error.size(), d.max_center_of_mass_distance);
  std::printf("  Newmark step: fine %.3f ms, this run %.3f ms (%d and %d elastic steps): %.1fx faster\n",
              1e3 * d.fine_seconds_per_step, 1e3 * d.model_seconds_per_step, d.fine_steps, d.model_steps,
              d.model_seconds_per_step > 0 ? d.fine_seconds_per_step / d.model_seconds_per_step : 0.0);
}

}  // namespace

int main(int argc, char** argv) {
  StageApp app("msfab-dynamics", "Implicit Newmark dynamics with frictional contact and impact (thesis ch. 4)");
  app.add_common_options();
  app.set_default_config(kDefaultDynamicsScene);
  std::vector<double> marker;
  std::string marker_csv;
  app.option("--marker", marker, "rest position X Y Z of a tracked node (the node nearest to it)").values(3);
  app.option("--marker-csv", marker_csv, "write the tracked node's position at every step as CSV (t,x,y,z)");
  CoarseningRequest coarsening;
  add_coarsening_options(app, coarsening, false);
  std::string reference;
  app.option("--reference", reference,
             "a msfab.trajectory of the same scene run fine (same time step and frames): report this "
             "run's difference from it frame by frame and the speedup");
  return app.run(argc, argv, [&](StageContext& ctx) {
    if (marker_csv.empty() != marker.empty()) throw InputError("--marker and --marker-csv go together");
    const std::string& out = ctx.require_out();

    // 1. Scene.
    if (coarsening.level == 0 && (!coarsening.database.empty() || coarsening.material != "ddfem"))
      throw InputError("--coarse-material and --database need --coarsen 1 or 2");
    const DynamicsScene scene = read_dynamics_scene(ctx.config, coarsening);
    ctx.finish_config();
    const Trajectory fine = reference.empty() ? Trajectory{} : read_trajectory_artifact(reference);
    if (!reference.empty()) check_fine_reference(scene, fine, reference);
    ctx.check_out_folder();
    ctx.check_memory(dynamics_peak_bytes(scene),
                     fmt::format("a run of {} elements over {} s with a frame every {} steps",
                                 scene.model.mesh.num_elements(), scene.duration, scene.output_every),
                     "use a coarser geometry.voxel_size, a larger simulation.output_every or a shorter duration");
    spdlog::info("scene '{}': {} elements, {} DOFs, {} obstacles, contact {}, friction {}, impact {}, h = {} s, {} s",
                 scene.name, scene.model.mesh.num_elements(), scene.model.mesh.num_dofs(), scene.model.obstacles.size(),
                 scene.model.contact ? "on" : "off", scene.model.friction ? "on" : "off",
                 impact_model_name(scene.model.impact), scene.newmark.time_step, scene.duration);
    if (scene.coarsening)
      spdlog::info("coarsened to level {} with {} materials: {} elements, {} distinct blocks, {:.1f} ms{}",
                   coarsening.level, coarsening.material, scene.model.mesh.num_elements(),
                   scene.coarsening->coarse.stats.distinct_combinations, 1e3 * scene.coarsening->coarse.seconds,
                   scene.coarsening->coarse.fallback_blocks
                       ? fmt::format(" ({} block kinds without a database fit coarsened {})",
                                     scene.coarsening->coarse.fallback_blocks, coarsening.fallback)
                       : std::string());

    // 2-4. Preload, release, dynamics and flight.
    const std::uint64_t total_steps = static_cast<std::uint64_t>(std::ceil(scene.duration / scene.newmark.time_step));
    Progress progress("dynamics steps", total_steps);
    RunCallbacks callbacks;
    MarkerTrace trace;
    if (!marker.empty()) trace.node = nearest_rest_node(scene, Vec3(marker[0], marker[1], marker[2]));
    callbacks.on_step = [&](double t, const VecX& q) {
      progress.tick();
      if (trace.node >= 0) trace.add(t, q);
    };
    Trajectory trajectory = run_dynamics_scene(scene, callbacks);
    progress.done();
    if (trace.node >= 0) write_marker_csv(marker_csv, trace);
    if (scene.coarsening) trajectory.coarsening = coarsening_record(*scene.coarsening);
    TrajectoryDifference difference;
    if (!reference.empty()) {
      difference = compare_with_fine(scene, trajectory, fine, reference);
      trajectory.comparison = comparison_record(difference, reference);
    }

    // 5. Artifact.
    TrajectoryProvenance provenance;
    provenance.config_text = ctx.config.resolved_text();
    provenance.seed = ctx.options.seed;
    provenance.inputs = scene.geometry_files;
    if (!coarsening.database.empty()) provenance.inputs.push_back(coarsening.database);
    if (!reference.empty()) provenance.inputs.push_back(reference);
    const std::string xmf = write_trajectory_artifact(out, trajectory, provenance);

    print_summary(scene, trajectory);
    std::printf("  artifact: %s\n  ParaView: %s\n", out.c_str(), xmf.c_str());
    if (!reference.empty()) print_difference(difference);
  });
}
