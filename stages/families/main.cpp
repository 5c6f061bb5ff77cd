// msfab-families: discovery of extremal microstructure families and their
// parametric templates (thesis §3.3, Fig. 3-4 to 3-12).
//
//   1. select the structures of a gamut in a property window (e.g. the
//      auxetic ones, ν < 0), optionally only those near the gamut boundary
//   2. smoothed voxel fields; distance = RMS difference minimized over
//      periodic translations
//   3. Isomap: k-nearest-neighbour graph, geodesic distances, classical MDS
//   4. Gaussian mixture clusters in the embedding, their number chosen by
//      BIC; clusters with at least `min_members` members are the families
//   5. per family: the representative (the member nearest its cluster's
//      mean) gets a template from its skeleton (one cuboid beam per edge of
//      the simplified skeleton graph in the fundamental tetrahedron), fitted
//      by gradient descent
//   6. the template refitted to every member; members it cannot reproduce
//      (voxel difference above `max_voxel_difference`) are dropped
//   7. principal component regression of the members' properties on their
//      parameters: two reduced parameters per family
//   8. write `msfab.families` and a picture per family
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>

#include "cli/progress.hpp"
#include "cli/stage_app.hpp"
#include "core/errors.hpp"
#include "core/timing.hpp"
#include "families/beam_template.hpp"
#include "families/families_artifact.hpp"
#include "families/family_selection.hpp"
#include "families/gaussian_mixture.hpp"
#include "families/isomap.hpp"
#include "families/structure_distance.hpp"
#include "families/template_fit.hpp"
#include "family_pictures.hpp"
#include "gamut/gamut_artifact.hpp"
#include "gamut/microstructure_set.hpp"

using namespace msfab;

namespace {

constexpr const char* kDefaults = R"(
selection:
  nu: [-1.0, 0.0]          # Poisson's ratio window (default: the auxetic structures)
  E: [0.0, 1.0]            # Young's modulus window, relative to the stiff material
  density: [0.0, 1.0]      # stiff-material fraction window
  boundary_margin: -1      # >= 0 (needs --gamut): only structures with Phi >= -margin, near the boundary
distance:
  sigma: 1.0               # Gaussian blur of the solid indicator, voxels (of the pooled grid)
  pool: 1                  # average-pool the cells by this factor first (64^3 -> 32^3 with 2)
isomap:
  neighbours: 10           # k of the nearest-neighbour graph
  dimensions: 3            # embedding dimensions (thesis: 3)
  connect: true            # join separate graph components by their shortest gaps (false: embed the largest only)
clusters:
  min: 1                   # mixture sizes tried; the smallest BIC wins
  max: 8
  restarts: 4
  min_variance: 0.01       # smallest cluster variance, relative to the embedding's: no clusters of near-duplicates
min_members: 200           # clusters with at least this many members are families (thesis: > 200)
template:
  threshold: 0.02          # skeleton path simplification, unit-cell units (thesis: 0.02)
  caps: true               # dome caps at the beam ends
  width: 1.0               # voxels: blur of target and template in the fit
  iterations: 200          # gradient steps for the representative
  member_iterations: 40    # gradient steps refitting the template to each member
  max_member_fits: 300     # at most this many members per family are refitted (evenly spread)
  max_voxel_difference: 0.05  # members whose refit differs more are dropped (thesis: 5%)
reduced:
  parameters: 2            # reduced parameters per family (Appendix A: 2)
  variance_kept: 0.99      # principal components kept
plots: true                # <stem>.plots/family<k>.png
)";

struct Settings {
  SelectionOptions selection;
  FieldOptions field;
  IsomapOptions isomap;
  int clusters_min = 1, clusters_max = 8, restarts = 4;
  double min_variance = 1e-2;
  int min_members = 200;
  TemplateFitOptions fit;
  int member_iterations = 40, max_member_fits = 300;
  double max_voxel_difference = 0.05;
  ReductionOptions reduction;
  bool plots = true;
};

void read_window(const Config& config, const std::string& key, double* lo, double* hi) {
  const std::vector<double> w = config.get_or<std::vector<double>>(key, {*lo, *hi});
  if (w.size() != 2 || !(w[0] <= w[1])) config.fail(key, "must be [low, high] with low <= high");
  *lo = w[0], *hi = w[1];
}

Settings read_settings(const Config& config) {
  Settings s;
  PropertyWindow& w = s.selection.window;
  w.nu_max = 0.0;
  read_window(config, "selection.nu", &w.nu_min, &w.nu_max);
  read_window(config, "selection.E", &w.E_min, &w.E_max);
  read_window(config, "selection.density", &w.density_min, &w.density_max);
  s.selection.boundary_margin = config.get_or<double>("selection.boundary_margin", -1.0);
  s.field.sigma = config.get_or<double>("distance.sigma", 1.0);
  if (!(s.field.sigma >= 0)) config.fail("distance.sigma", "must be >= 0");
  s.field.pool_factor = config.get_or<int>("distance.pool", 1);
  if (s.field.pool_factor < 1) config.fail("distance.pool", "must be >= 1");
  s.isomap.neighbors = config.get_or<int>("isomap.neighbours", 10);
  if (s.isomap.neighbors < 1) config.fail("isomap.neighbours", "must be >= 1");
  s.isomap.dimensions = config.get_or<int>("isomap.dimensions", 3);
  if (s.isomap.dimensions < 1 || s.isomap.dimensions > 5) config.fail("isomap.dimensions", "must be 1..5");
  s.isomap.connect = config.get_or<bool>("isomap.connect", true);
  s.clusters_min = config.get_or<int>("clusters.min", 1);
  s.clusters_max = config.get_or<int>("clusters.max", 8);
  if (s.clusters_min < 1 || s.clusters_max < s.clusters_min)
    config.fail("clusters.max", "needs 1 <= clusters.min <= clusters.max");
  s.restarts = config.get_or<int>("clusters.restarts", 4);
  if (s.restarts < 1) config.fail("clusters.restarts", "must be >= 1");
  s.min_variance = config.get_or<double>("clusters.min_variance", 1e-2);
  if (!(s.min_variance >= 0 && s.min_variance < 1)) config.fail("clusters.min_variance", "must be in [0, 1)");
  s.min_members = config.get_or<int>("min_members", 200);
  if (s.min_members < 3) config.fail("min_members", "must be >= 3 (the reduction regresses on the members)");
  s.fit.skeleton.tolerance = config.get_or<double>("template.threshold", 0.02);
  if (!(s.fit.skeleton.tolerance > 0)) config.fail("template.threshold", "must be > 0");
  s.fit.caps = config.get_or<bool>("template.caps", true);
  s.fit.width = config.get_or<double>("template.width", 1.0);
  if (!(s.fit.width > 0)) config.fail("template.width", "must be > 0");
  s.fit.max_iterations = config.get_or<int>("template.iterations", 200);
  if (s.fit.max_iterations < 0) config.fail("template.iterations", "must be >= 0");
  s.member_iterations = config.get_or<int>("template.member_iterations", 40);
  if (s.member_iterations < 0) config.fail("template.member_iterations", "must be >= 0");
  s.max_member_fits = config.get_or<int>("template.max_member_fits", 300);
  if (s.max_member_fits < 3) config.fail("template.max_member_fits", "must be >= 3");
  s.max_voxel_difference = config.get_or<double>("template.max_voxel_difference", 0.05);
  if (!(s.max_voxel_difference > 0 && s.max_voxel_difference <= 1))
    config.fail("template.max_voxel_difference", "must be in (0, 1]");
  s.reduction.reduced = config.get_or<int>("reduced.parameters", 2);
  if (s.reduction.reduced < 1 || s.reduction.reduced > 8) config.fail("reduced.parameters", "must be 1..8");
  s.reduction.variance_kept = config.get_or<double>("reduced.variance_kept", 0.99);
  if (!(s.reduction.variance_kept > 0 && s.reduction.variance_kept <= 1))
    config.fail("reduced.variance_kept", "must be in (0, 1]");
  s.plots = config.get_or<bool>("plots", true);
  return s;
}

VoxelGrid cell_of(const MicrostructureSet& set, std::int64_t s) {
  VoxelGrid cell(set.nx, set.ny, set.nz, 1.0 / set.nx);
  cell.ids = set.items[std::size_t(s)].ids;
  return cell;
}

// Peak memory of steps 2-3 (docs/cli.md, "Memory"): per structure its
// smoothed field and half spectrum (about 16 B per pooled voxel), and the
// Isomap matrices of selected^2 entries (distances, geodesic distances,
// the double-centred Gram matrix and its eigen-decomposition: about 40 B
// per pair).
void check_distance_memory(const StageContext& ctx, std::size_t selected, int pooled_n) {
  const double m = double(selected);
  ctx.check_memory(16.0 * m * std::pow(double(pooled_n), 3) + 40.0 * m * m,
                   "distances between " + std::to_string(selected) + " selected structures",
                   "narrow the selection window or pool the fields (distance.pool)");
}

// The members a family's template is refitted to: all, or an even spread.
std::vector<std::size_t> members_to_fit(std::size_t members, int max_fits) {
  std::vector<std::size_t> chosen;
  if (members <= std::size_t(max_fits)) {
    chosen.resize(members);
    std::iota(chosen.begin(), chosen.end(), std::size_t(0));
  } else {
    for (int i = 0; i < max_fits; ++i) chosen.push_back(std::size_t(double(i) * double(members) / max_fits));
  }
  return chosen;
}

// Steps 5-7 for one family.
void fit_family(FamilyRecord& fam, const MicrostructureSet& set, const Settings& settings, const std::string& name) {
  const VoxelGrid rep = cell_of(set, fam.representative);
  const TemplateFit rep_fit = fit_template(rep, settings.fit);
  fam.caps = rep_fit.fitted.caps;
  fam.representative_template = template_parameters(rep_fit.fitted);
  fam.representative_difference = rep_fit.voxel_difference;
  spdlog::info("{}: representative {} -> {} beams, voxel difference {:.2f}% ({} evaluations)", name, fam.representative,
               rep_fit.fitted.beams.size(), 100 * rep_fit.voxel_difference, rep_fit.evaluations);

  const std::size_t n = fam.members.size();
  const Eigen::Index p = fam.representative_template.size();
  fam.member_difference.assign(n, std::numeric_limits<double>::quiet_NaN());
  fam.member_kept.assign(n, 0);
  fam.member_parameters = MatX::Constant(Eigen::Index(n), p, std::numeric_limits<double>::quiet_NaN());
  const std::vector<std::size_t> chosen = members_to_fit(n, settings.max_member_fits);
  TemplateFitOptions member_options = settings.fit;
  member_options.max_iterations = settings.member_iterations;
  Progress progress(name + ": refitting the template", std::uint64_t(chosen.size()));
  // Each member's fit is serial and independent: the result does not depend
  // on the thread count.
#pragma omp parallel for schedule(dynamic, 1)
  for (std::size_t c = 0; c < chosen.size(); ++c) {
    const std::size_t i = chosen[c];
    const TemplateFit fit = refine_template(cell_of(set, fam.members[i]), rep_fit.fitted, member_options);
    fam.member_difference[i] = fit.voxel_difference;
    fam.member_parameters.row(Eigen::Index(i)) = template_parameters(fit.fitted).transpose();
    fam.member_kept[i] = fit.voxel_difference <= settings.max_voxel_difference;
    progress.tick();
  }
  progress.done();

  std::vector<Eigen::Index> rows;
  for (std::size_t i = 0; i < n; ++i)
    if (fam.member_kept[i]) rows.push_back(Eigen::Index(i));
  spdlog::info("{}: template refitted to {} of {} members, {} within {:.0f}% voxel difference", name, chosen.size(), n,
               rows.size(), 100 * settings.max_voxel_difference);
  if (rows.size() < 3) {
    spdlog::warn("{}: fewer than 3 members fit the template; no reduced parameters", name);
    return;
  }
  MatX P(Eigen::Index(rows.size()), p), Y(Eigen::Index(rows.size()), 2);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const Microstructure& m = set.items[std::size_t(fam.members[std::size_t(rows[k])])];
    P.row(Eigen::Index(k)) = fam.member_parameters.row(rows[k]);
    Y(Eigen::Index(k), 0) = std::log10(m.properties[0] / set.E_stiff);
    Y(Eigen::Index(k), 1) = m.properties[1];
  }
  try {
    fam.reduced = reduce_template_parameters(P, Y, settings.reduction);
    fam.has_reduced = true;
    spdlog::info("{}: {} principal components ({:.1f}% of the spread), R^2 log E {:.3f}, nu {:.3f}", name,
                 fam.reduced.components, 100 * fam.reduced.explained_variance, fam.reduced.regression_r2[0],
                 fam.reduced.regression_r2[1]);
  } catch (const InputError& e) {
    spdlog::warn("{}: no reduced parameters: {}", name, e.what());
  }
}

}  // namespace

int main(int argc, char** argv) {
  StageApp app("msfab-families", "Extremal microstructure families and their parametric templates (thesis 3.3)");
  app.add_common_options();
  app.set_default_config(kDefaults);
  std::string structures_path, gamut_path;
  app.option("--structures", structures_path, "msfab.microstructures artifact (3D cubic)").type_name("FILE").required();
  app.option("--gamut", gamut_path, "msfab.gamut artifact, for selection.boundary_margin").type_name("FILE");
  return app.run(argc, argv, [&](StageContext& ctx) {
    const auto start = std::chrono::steady_clock::now();
    const Settings settings = read_settings(ctx.config);
    ctx.finish_config();
    const std::string out = ctx.require_out();
    ctx.check_out_folder();
    if (settings.selection.boundary_margin >= 0 && gamut_path.empty())
      ctx.config.fail("selection.boundary_margin", "needs --gamut (the level set of the boundary)");

    // 1. Selection.
    const MicrostructureSet set = read_microstructures_artifact(structures_path);
    Gamut gamut;
    if (!gamut_path.empty()) gamut = read_gamut_artifact(gamut_path);
    FamiliesResult result;
    result.resolution = set.nx;
    result.E_stiff = set.E_stiff;
    result.decades = set.decades;
    result.stiff_E = set.stiff.E;
    result.stiff_nu = set.stiff.nu;
    result.selection =
        select_structures(set, settings.selection, gamut_path.empty() ? nullptr : &gamut.level_set, structures_path);
    const std::size_t selected = result.selection.size();
    if (selected == 0)
      throw InputError(structures_path + ": no structure lies in the selection (" + std::to_string(set.items.size()) +
                       " structures; widen selection.nu / E / density or the boundary margin)");
    if (selected < std::size_t(settings.min_members) || selected <= std::size_t(settings.isomap.neighbors))
      throw InputError(
          structures_path + ": the selection holds " + std::to_string(selected) +
          " structures; family discovery needs at least min_members = " + std::to_string(settings.min_members) +
          " and more than isomap.neighbours = " + std::to_string(settings.isomap.neighbors));
    spdlog::info("{} of {} structures selected ({}^3 voxels)", selected, set.items.size(), set.nx);
    check_distance_memory(ctx, selected, set.nx / settings.field.pool_factor);

    // 2. Distances.
    std::vector<VoxelField> fields(selected);
    for (std::size_t i = 0; i < selected; ++i)
      fields[i] = smoothed_field(set.items[std::size_t(result.selection[i])].ids, set.nx, settings.field);
    const auto t_distance = std::chrono::steady_clock::now();
    const MatX D = pairwise_structure_distances(fields);
    spdlog::info("pairwise distances: {} pairs in {:.1f} s", selected * (selected - 1) / 2, seconds_since(t_distance));

    // 3. Embedding.
    const IsomapResult embedding = isomap(D, settings.isomap);
    if (embedding.components > 1)
      spdlog::info("the {}-nearest-neighbour graph has {} components{}", settings.isomap.neighbors,
                   embedding.components, settings.isomap.connect ? ", joined by their shortest gaps" : "");
    if (!embedding.left_out.empty())
      spdlog::warn("{} structures are not connected to the largest neighbour-graph component and are left out",
                   embedding.left_out.size());
    result.embedding =
        MatX::Constant(Eigen::Index(selected), settings.isomap.dimensions, std::numeric_limits<double>::quiet_NaN());
    for (std::size_t k = 0; k < embedding.kept.size(); ++k)
      result.embedding.row(embedding.kept[k]) = embedding.coordinates.row(Eigen::Index(k));
    result.eigenvalues = embedding.eigenvalues;
    result.residual_variance = embedding.residual_variance;
    spdlog::info("isomap: {} dimensions, residual variance {:.4f}", settings.isomap.dimensions,
                 embedding.residual_variance);

    // 4. Clusters.
    GmmOptions gmm;
    gmm.restarts = settings.restarts;
    gmm.min_variance = settings.min_variance;
    gmm.seed = ctx.options.seed;
    const int kmax = std::min<int>(settings.clusters_max, int(embedding.kept.size()) - 1);
    const GmmSelection clusters =
        select_gaussian_mixture(embedding.coordinates, std::min(settings.clusters_min, kmax), kmax, gmm);
    result.bic_components = clusters.components;
    result.bic = clusters.bic;
    result.clusters = int(clusters.best.weights.size());
    result.labels.assign(selected, -1);
    for (std::size_t k = 0; k < embedding.kept.size(); ++k)
      result.labels[std::size_t(embedding.kept[k])] = clusters.best.labels[k];
    spdlog::info("mixture: {} clusters by BIC (sizes {})", result.clusters, fmt::join(clusters.best.sizes, ", "));

    // Families: clusters with enough members, largest first; the
    // representative is the member nearest its cluster's mean.
    std::vector<int> order(std::size_t(result.clusters));
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return clusters.best.sizes[std::size_t(a)] > clusters.best.sizes[std::size_t(b)];
    });
    result.family_of.assign(selected, -1);
    for (int c : order) {
      if (clusters.best.sizes[std::size_t(c)] < settings.min_members) continue;
      FamilyRecord fam;
      double best = std::numeric_limits<double>::infinity();
      const int family = int(result.families.size());
      for (std::size_t k = 0; k < embedding.kept.size(); ++k) {
        if (clusters.best.labels[k] != c) continue;
        const std::size_t i = std::size_t(embedding.kept[k]);
        fam.members.push_back(result.selection[i]);
        result.family_of[i] = family;
        const double d = (embedding.coordinates.row(Eigen::Index(k)) - clusters.best.means.row(c)).squaredNorm();
        if (d < best) best = d, fam.representative = result.selection[i];
      }
      result.families.push_back(std::move(fam));
    }
    std::printf(
        "msfab-families: %zu structures selected, %zu embedded (%d graph components), %d clusters, %zu "
        "families of >= %d members\n",
        selected, embedding.kept.size(), embedding.components, result.clusters, result.families.size(),
        settings.min_members);

    // 5-7. Templates and reduced parameters.
    for (std::size_t f = 0; f < result.families.size(); ++f) {
      FamilyRecord& fam = result.families[f];
      const std::string name = "family " + std::to_string(f + 1);
      double e[2] = {1e300, -1e300}, nu[2] = {1e300, -1e300}, g[2] = {1e300, -1e300};
      for (std::int64_t s : fam.members) {
        const VecX& p = set.items[std::size_t(s)].properties;
        const double E = p[0] / set.E_stiff, ratio = shear_modulus_ratio(p[0], p[1], p[2]);
        e[0] = std::min(e[0], E), e[1] = std::max(e[1], E);
        nu[0] = std::min(nu[0], p[1]), nu[1] = std::max(nu[1], p[1]);
        g[0] = std::min(g[0], ratio), g[1] = std::max(g[1], ratio);
      }
      std::copy(e, e + 2, fam.E_range), std::copy(nu, nu + 2, fam.nu_range), std::copy(g, g + 2, fam.shear_ratio_range);
      fit_family(fam, set, settings, name);
      int kept = 0;
      for (char k : fam.member_kept) kept += k;
      std::printf(
          "  family %zu: %zu members, E %.3g..%.3g, nu %.3f..%.3f, G' %.3f..%.3f; template %lld beams, "
          "representative differs by %.2f%%, %d members fit within %.0f%%%s\n",
          f + 1, fam.members.size(), fam.E_range[0], fam.E_range[1], fam.nu_range[0], fam.nu_range[1],
          fam.shear_ratio_range[0], fam.shear_ratio_range[1],
          static_cast<long long>(fam.representative_template.size() / kBeamParameters),
          100 * fam.representative_difference, kept, 100 * settings.max_voxel_difference,
          fam.has_reduced ? "" : " (no reduced parameters)");
    }

    // 8. Output.
    std::vector<std::string> inputs{structures_path};
    if (!gamut_path.empty()) inputs.push_back(gamut_path);
    write_families_artifact(out, result, "msfab-families", ctx.config.resolved_text(), inputs, ctx.options.seed);
    if (settings.plots) {
      const std::string folder = picture_folder_for(out);
      write_family_pictures(folder, result, set);
      spdlog::info("family pictures in {}", folder);
    }
    std::printf("msfab-families: %.1f s; %s\n", seconds_since(start), out.c_str());
  });
}
