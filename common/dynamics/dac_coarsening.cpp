#include "dynamics/dac_coarsening.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/errors.hpp"

namespace msfab {

namespace {

// Orders outside this range are not asymptotic convergence of a
// discretization: below it the changes hardly shrink, above it the
// sequence has stopped moving.
constexpr double kMinObservedOrder = 0.05;
constexpr double kMaxObservedOrder = 20.0;

void check_options(const DacOptions& o) {
  auto bad = [](const std::string& what) { throw InputError("DAC coarsening options: " + what); };
  if (o.max_level < o.first_level) bad("max_level must be >= first_level");
  if (o.num_modes < 1) bad("num_modes must be at least 1");
  if (!(o.convergence_tolerance > 0)) bad("convergence_tolerance must be positive");
  if (!(o.shape_tolerance > 0)) bad("shape_tolerance must be positive");
  if (o.match_window < 0) bad("match_window must be >= 0");
  if (!(o.accuracy_tolerance > 0)) bad("accuracy_tolerance must be positive");
}

// Ratio of the finer change to the coarser one that f0 + c h^p gives at
// sizes h0 > h1 > h2; it falls from ln(h1/h2) / ln(h0/h1) at p -> 0
// towards 0 as p grows.
double change_ratio(double p, const std::array<double, 3>& h) {
  return (std::pow(h[1], p) - std::pow(h[2], p)) / (std::pow(h[0], p) - std::pow(h[1], p));
}

// Frequency of reference mode j on a level, by shape: the level's mode
// matched to j at the smallest distance, or its own mode j where none was.
double frequency_of_reference_mode(const DacLevelReport& level, int j) {
  int best = -1;
  for (size_t i = 0; i < level.matches.size(); ++i)
    if (level.matches[i].reference_mode == j &&
        (best < 0 || level.matches[i].distance < level.matches[static_cast<size_t>(best)].distance))
      best = static_cast<int>(i);
  return level.frequencies(best >= 0 ? best : j);
}

}  // namespace

FrequencyLimit extrapolate_frequency(const std::array<double, 3>& f, const std::array<double, 3>& h) {
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(f[i]) || !std::isfinite(h[i]) || !(h[i] > 0))
      throw InputError("frequency extrapolation: sizes must be positive and values finite");
  if (!(h[0] > h[1] && h[1] > h[2])) throw InputError("frequency extrapolation: element sizes must decrease");
  FrequencyLimit out;
  out.limit = f[2];
  const double coarse_change = f[1] - f[0], fine_change = f[2] - f[1];
  if (fine_change == 0.0) {  // no change left to extrapolate
    out.monotone = coarse_change != 0.0;
    out.order = out.monotone ? kMaxObservedOrder : 0.0;
    return out;
  }
  const double ratio = fine_change / coarse_change;
  if (!(ratio > 0) || !(ratio < change_ratio(kMinObservedOrder, h))) return out;
  // change_ratio falls monotonically in p: bisection on [min, max] order.
  double lo = kMinObservedOrder, hi = kMaxObservedOrder;
  if (ratio <= change_ratio(hi, h)) {
    lo = hi;
  } else {
    for (int it = 0; it < 200 && hi - lo > 1e-12 * hi; ++it) {
      const double mid = 0.5 * (lo + hi);
      (change_ratio(mid, h) > ratio ? lo : hi) = mid;
    }
  }
  const double p = 0.5 * (lo + hi);
  const double h1p = std::pow(h[1], p), h2p = std::pow(h[2], p);
  out.order = p;
  out.monotone = true;
  out.limit = f[2] + fine_change * h2p / (h1p - h2p);
  return out;
}

DacResult dac_geometric_coarsening(const DacLevelBuilder& build, const DacOptions& options) {
  check_options(options);
  ModalOptions modal = options.modal;
  modal.num_modes = options.num_modes + options.match_window;
  modal.skip_rigid = true;
  const int k = options.num_modes;

  DacResult result;
  std::vector<ModeShapeSurface> surfaces;
  std::vector<ModalResult> modes;
  for (int level = options.first_level; level <= options.max_level; ++level) {
    DacLevel built = build(level);
    DacLevelReport report;
    report.level = level;
    report.elements = built.mesh.num_elements();
    report.dofs = built.mesh.num_dofs();
    report.element_size = built.element_size;
    modes.push_back(modal_analysis(built.mesh, built.density, built.fixed, modal));
    surfaces.push_back(mode_shape_surface(built.mesh));
    report.frequencies = modes.back().frequencies;
    if (!result.levels.empty()) {
      const VecX& previous = result.levels.back().frequencies;
      for (int i = 0; i < k; ++i)
        report.frequency_change =
            std::max(report.frequency_change, std::abs(report.frequencies(i) - previous(i)) / report.frequencies(i));
    }
    result.levels.push_back(std::move(report));
    if (result.levels.size() > 1 && result.levels.back().frequency_change < options.convergence_tolerance) {
      result.converged = true;
      break;
    }
  }
  const size_t reference = result.levels.size() - 1;
  result.convergent_level = result.levels[reference].level;

  bool chosen = false;
  for (size_t l = 0; l < result.levels.size(); ++l) {
    DacLevelReport& report = result.levels[l];
    report.matches = match_modes(surfaces[reference], modes[reference].modes, surfaces[l], modes[l].modes.leftCols(k),
                                 options.match_window, options.distance);
    report.max_distance = 0;
    for (const ModeMatch& m : report.matches) report.max_distance = std::max(report.max_distance, m.distance);
    report.within_tolerance = report.max_distance <= options.shape_tolerance;
    if (report.within_tolerance && !chosen) {
      chosen = true;
      result.chosen_index = l;
      result.chosen_level = report.level;
    }
  }
  // The reference matches itself at distance 0, so a level is always chosen.
  result.chosen_modes = modes[result.chosen_index];
  result.convergent_modes = modes[reference];

  // Converged frequencies and the accurate level.
  const size_t n = result.levels.size();
  for (int j = 0; j < k; ++j) {
    FrequencyLimit limit;
    limit.limit = result.levels[reference].frequencies(j);
    if (n >= 3) {
      std::array<double, 3> f{}, h{};
      for (int t = 0; t < 3; ++t) {
        const DacLevelReport& l = result.levels[n - 3 + static_cast<size_t>(t)];
        f[static_cast<size_t>(t)] = frequency_of_reference_mode(l, j);
        h[static_cast<size_t>(t)] = l.element_size;
      }
      if (h[0] > h[1] && h[1] > h[2]) limit = extrapolate_frequency(f, h);
    }
    result.limits.push_back(limit);
  }
  for (size_t l = 0; l < n; ++l) {
    DacLevelReport& report = result.levels[l];
    report.limit_error = report.mean_limit_error = 0;
    for (int j = 0; j < k; ++j) {
      const double e = std::abs(frequency_of_reference_mode(report, j) / result.limits[j].limit - 1);
      report.limit_error = std::max(report.limit_error, e);
      report.mean_limit_error += e / k;
    }
    report.accurate = report.limit_error <= options.accuracy_tolerance;
    if (report.accurate && result.accurate_level < 0) {
      result.accurate_level = report.level;
      result.accurate_index = l;
    }
  }
  return result;
}

}  // namespace msfab
