// msfab-dac-calibrate: dynamics-aware coarsening (thesis §4.3) of one
// material of a dynamics scene:
//
//   1. read the calibration rig (a dynamics scene: geometry, clamp,
//      material with its reference modulus E_m)
//   2. optionally search the coarsest voxel size whose first modes match
//      the convergent mesh's within the Hausdorff tolerance (§4.3.1)
//   3. modal analysis K x = lambda M x of the chosen mesh (Eq. 4.15)
//   4. target frequency f_t and decay d_t: given, or extracted from a
//      tracked marker (CSV) by harmonic inversion
//   5. lambda_t = (2 pi f_t)^2 + d_t^2, b = 2 d_t / lambda_t, a = 0,
//      E_n = lambda_t / lambda_1^0 E_m (Eq. 4.16-4.18)
//   6. write the `msfab.dac_model` artifact; scenes use it through a
//      material's `dac_model:` key
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "dynamics/dac_calibration.hpp"
#include "dynamics/dac_coarsening.hpp"
#include "dynamics/dac_model_artifact.hpp"
#include "dynamics/dynamics_scene.hpp"
#include "dynamics/harmonic_inversion.hpp"
#include "dynamics/marker_track.hpp"
#include "dynamics/modal_analysis.hpp"

using namespace msfab;

namespace {

constexpr const char* kDefaultCalibration = R"yaml(
# The cantilever calibration rig with a target measured on it.
scene: configs/dynamics/cantilever_pluck.yaml
material: rigur
target: {frequency: 340.0, decay: 20.0}   # a stand-in for a measured rig
modes: 4
# search_levels: 2          # also mesh the rig at 1..2 halvings of its voxel: calibrate the coarsest
#                           # whose first modes' shapes match the finest's (§4.3.1), and report the
#                           # converged frequencies and the accurate mesh
# accuracy_tolerance: 0.05  # accurate mesh: first modes within this fraction of the converged values
)yaml";

DynamicsScene scene_at_voxel_size(const std::string& path, double voxel_size) {
  Config c = Config::load_file(path);
  if (voxel_size > 0) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "geometry.voxel_size=%.17g", voxel_size);
    c.apply_override(buf);
  }
  return read_dynamics_scene(c);
}

// A rig without damping rings at constant amplitude, and harmonic inversion
// returns a decay scattered about zero by the other modes and the noise in
// the track, of either sign. A decay within three standard errors of zero
// (or below what the record's length resolves in double precision) cannot
// be told from none: the rig is taken as undamped. A track that clearly
// grows is not a free decay and cannot be calibrated on.
double undamped_if_unresolved(const std::string& track_path, double decay, double uncertainty, double duration) {
  const double resolvable = std::max(3 * uncertainty, std::sqrt(std::numeric_limits<double>::epsilon()) / duration);
  if (std::abs(decay) <= resolvable) {
    spdlog::info("{}: decay {:.3g} 1/s lies within {:.2g} of zero: the rig is taken as undamped (d = 0)", track_path,
                 decay, resolvable);
    return 0.0;
  }
  if (decay > 0) return decay;
  throw InputError(track_path + ": the tracked oscillation grows (decay " + std::to_string(decay) + " ± " +
                   std::to_string(uncertainty) + " 1/s): not the free decay of a rig, cannot calibrate on it");
}

// The search's levels, the converged frequencies and the accurate mesh
// (thesis Fig. 4-11: frequencies within the tolerance of their converged
// values), which is what a coarse DAC mesh is timed against.
void report_search(const DacResult& search, const DacOptions& options, double voxel_size) {
  const int num_modes = options.num_modes;
  for (const DacLevelReport& l : search.levels)
    spdlog::info(
        "level {}: {} elements, f1 {:.4f} Hz, frequency change {:.2f}%, shape distance {:.4f}, "
        "frequency error against the converged values: largest {:.2f}%, mean {:.2f}%",
        l.level, l.elements, l.frequencies.size() ? l.frequencies[0] : 0.0, 100 * l.frequency_change, l.max_distance,
        100 * l.limit_error, 100 * l.mean_limit_error);
  std::string limits;
  for (const FrequencyLimit& f : search.limits)
    limits +=
        f.monotone ? fmt::format(" {:.6g} (p {:.2f})", f.limit, f.order) : fmt::format(" {:.6g} (finest)", f.limit);
  std::printf(
      "  converged frequencies of the first %d modes (Hz; Richardson extrapolation over the three finest "
      "levels, observed order p):%s\n",
      num_modes, limits.c_str());
  const bool all_extrapolated =
      std::all_of(search.limits.begin(), search.limits.end(), [](const FrequencyLimit& f) { return f.monotone; });
  if (!search.converged && !all_extrapolated)
    std::printf(
        "  note: the levels neither converged (frequency change < %g%%) nor gave every mode a limit (three "
        "levels converging monotonically): the accurate mesh below is judged against the finest level\n",
        100 * options.convergence_tolerance);
  if (search.accurate_level < 0) {
    std::printf("  accurate mesh: none of the levels searched (finest: largest error %.2f%%)\n",
                100 * search.levels.back().limit_error);
    return;
  }
  const DacLevelReport& a = search.levels[search.accurate_index];
  std::printf(
      "  accurate mesh: level %d, voxel %.4g m, %d elements (first %d frequencies within %.2f%% of the "
      "converged values, mean %.2f%%)\n",
      a.level, voxel_size / std::pow(2.0, a.level), a.elements, num_modes, 100 * a.limit_error,
      100 * a.mean_limit_error);
}

}  // namespace

int main(int argc, char** argv) {
  StageApp app("msfab-dac-calibrate",
               "Dynamics-aware coarsening: numerical modulus and damping from a target (thesis §4.3)");
  app.add_common_options();
  app.set_default_config(kDefaultCalibration);
  return app.run(argc, argv, [&](StageContext& ctx) {
    const std::string& out = ctx.require_out();
    const Config& c = ctx.config;

    // 1. Rig.
    const std::string scene_path = c.get_path("scene");
    const std::string material = c.get<std::string>("material");
    const int num_modes = c.get_or<int>("modes", 4);
    if (num_modes < 1 || num_modes > 50) c.fail("modes", "must be in 1..50");
    const int search_levels = c.get_or<int>("search_levels", 0);
    if (search_levels < 0 || search_levels > 5) c.fail("search_levels", "must be in 0..5");
    const double accuracy_tolerance = c.get_or<double>("accuracy_tolerance", 0.05);
    if (!(accuracy_tolerance > 0 && accuracy_tolerance < 1)) c.fail("accuracy_tolerance", "must be in (0, 1)");
    const bool from_marker = c.has("marker_csv");
    if (from_marker == c.has("target")) c.fail("target", "give either target {frequency, decay} or marker_csv");
    double f_t = 0, d_t = 0;
    std::string marker_path, column;
    int inversion_modes = 1;
    if (from_marker) {
      marker_path = c.get_path("marker_csv");
      column = c.get_or("column", "");
      inversion_modes = c.get_or<int>("inversion_modes", 1);
    } else {
      f_t = c.require_positive<double>("target.frequency", "target frequency (Hz)");
      d_t = c.get<double>("target.decay");
      if (!(d_t >= 0)) c.fail("target.decay", "must be >= 0 (1/s)");
    }
    ctx.finish_config();
    const DynamicsScene rig = scene_at_voxel_size(scene_path, 0);
    int material_index = -1;
    for (size_t i = 0; i < rig.materials.size(); ++i)
      if (rig.materials[i].name == material) material_index = static_cast<int>(i);
    if (material_index < 0) c.fail("material", "the scene has no material '" + material + "'");
    const double E_m = rig.materials[material_index].E;
    ctx.check_out_folder();
    {
      // The finest mesh searched has 8^search_levels times the rig's elements.
      ModalOptions modal;
      modal.num_modes = num_modes;
      modal.skip_rigid = rig.model.fixed.empty();
      const double refinement = std::pow(8.0, search_levels);
      const double elements = refinement * rig.model.mesh.num_elements();
      ctx.check_memory(modal_analysis_peak_bytes(elements, refinement * rig.model.mesh.num_dofs(), modal),
                       fmt::format("the modes of {:.0f} elements ({} modes{})", elements, num_modes,
                                   search_levels > 0 ? fmt::format(", search_levels {}", search_levels) : ""),
                       "use fewer search_levels or a coarser geometry.voxel_size in the scene");
    }

    // 2-3. Mesh and modes.
    double voxel_size = rig.grid.voxel_size;
    ModalResult modes;
    DacResult search;
    if (search_levels > 0) {
      DacOptions options;
      options.num_modes = num_modes;
      options.max_level = search_levels;
      options.accuracy_tolerance = accuracy_tolerance;
      search = dac_geometric_coarsening(
          [&](int level) {
            const DynamicsScene s = scene_at_voxel_size(scene_path, rig.grid.voxel_size / std::pow(2.0, level));
            return DacLevel{s.model.mesh, s.model.density, s.model.fixed, s.grid.voxel_size};
          },
          options);
      voxel_size = rig.grid.voxel_size / std::pow(2.0, search.chosen_level);
      modes = search.chosen_modes;
      report_search(search, options, rig.grid.voxel_size);
    } else {
      ModalOptions options;
      options.num_modes = num_modes;
      options.skip_rigid = rig.model.fixed.empty();
      modes = modal_analysis(rig.model.mesh, rig.model.density, rig.model.fixed, options);
    }
    const double lambda1 = modes.eigenvalues(0);

    // 4. Target.
    double rms = 0;
    if (from_marker) {
      const MarkerTrack track = read_marker_track(marker_path, column);
      HarmonicInversionOptions inversion;
      inversion.num_modes = inversion_modes;
      const HarmonicFit fit = harmonic_inversion(track.values, track.sample_interval, inversion);
      const DampedMode& m = dominant_mode(fit);
      f_t = m.frequency;
      d_t = m.decay;
      rms = fit.rms_residual;
      spdlog::info(
          "{}: {} samples at {:.4g} s, dominant mode f = {:.6g} Hz, d = {:.6g} ± {:.2g} 1/s (rms residual {:.3g})",
          marker_path, track.values.size(), track.sample_interval, f_t, d_t, m.decay_uncertainty, rms);
      d_t = undamped_if_unresolved(marker_path, d_t, m.decay_uncertainty,
                                   double(track.values.size()) * track.sample_interval);
    }

    // 5. Numerical modulus and damping.
    const DacCalibration cal = calibrate_dac(f_t, d_t, lambda1, E_m);
    std::vector<double> lambdas(modes.eigenvalues.data(), modes.eigenvalues.data() + modes.eigenvalues.size());
    const std::vector<ModalResponse> after = calibrated_modes(lambdas, cal);

    // 6. Artifact.
    DacModel model;
    model.material = material;
    model.reference_modulus = E_m;
    model.youngs_modulus = cal.youngs_modulus;
    model.damping_a = cal.damping.a;
    model.damping_b = cal.damping.b;
    model.target_frequency = f_t;
    model.target_decay = d_t;
    model.target_eigenvalue = cal.target_eigenvalue;
    model.coarse_eigenvalues = modes.eigenvalues;
    model.voxel_size = voxel_size;
    model.elements = search_levels > 0 ? search.levels[search.chosen_index].elements : rig.model.mesh.num_elements();
    model.marker_rms = rms;
    write_dac_model_artifact(out, model, "msfab-dac-calibrate", c.resolved_text(),
                             from_marker ? std::vector<std::string>{marker_path} : std::vector<std::string>{},
                             ctx.options.seed);

    std::printf("msfab-dac-calibrate: material '%s' on '%s' (voxel %.4g m, %d elements)\n", material.c_str(),
                rig.name.c_str(), voxel_size, model.elements);
    std::printf("  target f_t = %.6g Hz, d_t = %.6g 1/s -> lambda_t = %.6g\n", f_t, d_t, cal.target_eigenvalue);
    std::printf("  E_m = %.6g Pa, lambda_1^0 = %.6g -> E_n = %.6g Pa (x%.4f), b = %.4e s, a = 0\n", E_m, lambda1,
                cal.youngs_modulus, cal.stiffness_scale, cal.damping.b);
    for (int i = 0; i < modes.eigenvalues.size(); ++i)
      std::printf("  mode %d: f with E_m %.6g Hz -> calibrated %.6g Hz, decay %.4g 1/s\n", i + 1, modes.frequencies(i),
                  after[i].frequency, after[i].decay);
    std::printf("  artifact: %s\n", out.c_str());
  });
}
