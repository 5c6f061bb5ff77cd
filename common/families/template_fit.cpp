#include "families/template_fit.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <string>

#include "core/errors.hpp"

namespace msfab {
namespace {

constexpr double kPi = 3.14159265358979323846;

void check_target(const VoxelGrid& c, const char* what) {
  if (c.nx != c.ny || c.ny != c.nz || c.nx < 3)
    throw InputError(std::string(what) + ": the target must be a cubic n x n x n cell with n >= 3, got " +
                     std::to_string(c.nx) + " x " + std::to_string(c.ny) + " x " + std::to_string(c.nz));
  if (c.ids.size() != std::size_t(c.nx) * c.ny * c.nz)
    throw InputError(std::string(what) + ": the target has " + std::to_string(c.ids.size()) + " voxel ids for " +
                     std::to_string(c.nx) + "^3 voxels");
}

void check_options(const TemplateFitOptions& o, const char* what) {
  auto bad = [&](const std::string& field, double v, const std::string& rule) {
    throw InputError(std::string(what) + ": option " + field + " must be " + rule + ", got " + std::to_string(v));
  };
  if (!(o.width > 0) || !std::isfinite(o.width)) bad("width", o.width, "> 0");
  if (o.max_iterations < 0) bad("max_iterations", o.max_iterations, ">= 0");
  if (!(o.relative_tolerance >= 0)) bad("relative_tolerance", o.relative_tolerance, ">= 0");
  if (!(o.difference_step > 0) || !std::isfinite(o.difference_step)) bad("difference_step", o.difference_step, "> 0");
  if (!(o.initial_step > 0) || !std::isfinite(o.initial_step)) bad("initial_step", o.initial_step, "> 0");
  if (!(o.merge_tolerance >= 0)) bad("merge_tolerance", o.merge_tolerance, ">= 0");
  if (!(o.restart_difference >= 0)) bad("restart_difference", o.restart_difference, ">= 0");
  if (o.max_restarts < 0) bad("max_restarts", o.max_restarts, ">= 0");
}

// The smoothed target and the objective of per-beam occupancies at the
// fundamental voxels, with the model at a given sharpening.
class FitProblem {
 public:
  FitProblem(const VoxelGrid& target, double width, double sharpening)
      : n_(target.nx),
        width_(width),
        sharpening_(sharpening),
        fv_(fundamental_voxels(target.nx)),
        target_(smooth_cell(target, width)) {}

  std::vector<double> occupancy(const Beam& b, bool caps) const { return beam_occupancy(b, caps, fv_, sharpening_); }
  std::vector<double> empty() const { return std::vector<double>(fv_.voxel.size(), 0.0); }

  // Objective of the union of two occupancy fields (either may be that of
  // several beams already): rasterize_template_smooth, compared voxel by
  // voxel with the smoothed target.
  double objective(const std::vector<double>& occ, const std::vector<double>* other = nullptr) const {
    ++evaluations;
    std::vector<double> cell(target_.size());
    for (std::size_t v = 0; v < cell.size(); ++v) {
      const int f = fv_.orbit_of[v];
      cell[v] = other ? std::max(occ[f], (*other)[f]) : occ[f];
    }
    const std::vector<double> model = periodic_blur(cell, n_, width_);
    double sum = 0;
    for (std::size_t v = 0; v < model.size(); ++v) sum += (model[v] - target_[v]) * (model[v] - target_[v]);
    return sum / double(model.size());
  }

  // The objective is J = |B m - t|^2 / N for the blur B (symmetric) and
  // the cell's occupancy m, so a change dm changes it by
  // 2 <B (B m - t), dm> / N to first order. Summed over each orbit, the
  // blurred residual weighs a change at the fundamental voxels: one blur
  // per gradient instead of one per probed parameter.
  std::vector<double> sensitivity(const std::vector<double>& occ) const {
    std::vector<double> cell(target_.size());
    for (std::size_t v = 0; v < cell.size(); ++v) cell[v] = occ[fv_.orbit_of[v]];
    std::vector<double> residual = periodic_blur(cell, n_, width_);
    for (std::size_t v = 0; v < residual.size(); ++v) residual[v] -= target_[v];
    const std::vector<double> back = periodic_blur(residual, n_, width_);
    std::vector<double> weight(occ.size(), 0.0);
    for (std::size_t v = 0; v < back.size(); ++v) weight[fv_.orbit_of[v]] += 2.0 * back[v] / double(back.size());
    return weight;
  }

  int n() const { return n_; }
  mutable int evaluations = 0;

 private:
  int n_;
  double width_, sharpening_;
  FundamentalVoxels fv_;
  std::vector<double> target_;
};

void take_max(std::vector<double>& into, const std::vector<double>& occ) {
  for (std::size_t f = 0; f < into.size(); ++f) into[f] = std::max(into[f], occ[f]);
}

Beam sized(Beam b, double r0, double r1, double theta) {
  b.r0 = std::max(r0, 0.0), b.r1 = std::max(r1, 0.0), b.theta = theta;
  return b;
}

// Coarse-to-fine search over one beam's section: a square section over a
// range of sizes, then aspect ratios and angles around the best, then a
// compass search with shrinking steps.
Beam search_section(const FitProblem& P, const Beam& start, bool caps) {
  const double h = 1.0 / P.n();
  Beam best = sized(start, h, h, start.theta);
  double value = P.objective(P.occupancy(best, caps));
  auto consider = [&](const Beam& b) {
    const double v = P.objective(P.occupancy(b, caps));
    if (v < value) value = v, best = b;
  };
  const double largest = std::min(0.25, 12 * h);
  for (double r = 0.5 * h; r <= largest + 1e-12; r += 0.5 * h) consider(sized(start, r, r, start.theta));
  const double r = std::sqrt(best.r0 * best.r1);
  for (int a = 0; a < 4; ++a)
    for (double s : {0.5, 0.7, 1.0, 1.4, 2.0}) {
      if (a == 0 && s == 1.0) continue;
      consider(sized(start, r * std::sqrt(s), r / std::sqrt(s), start.theta + a * kPi / 8));
    }
  double step[3] = {0.5 * h, 0.5 * h, kPi / 16};
  for (int round = 0; round < 4; ++round) {
    bool moved = true;
    for (int sweep = 0; moved && sweep < 20; ++sweep) {
      moved = false;
      for (int p = 0; p < 3; ++p)
        for (double sign : {1.0, -1.0}) {
          double q[3] = {best.r0, best.r1, best.theta};
          q[p] += sign * step[p];
          const double before = value;
          consider(sized(best, q[0], q[1], q[2]));
          moved = moved || value < before;
        }
    }
    for (double& s : step) s *= 0.5;
  }
  return best;
}

// Gradient descent at one sharpening: at most `iterations` gradients (the
// number computed is added to `used`), stopping once the last `window`
// accepted steps together lower the objective by less than `tolerance` of
// it. Each value is appended to `history`.
BeamTemplate refine(const FitProblem& P, const BeamTemplate& start, const TemplateFitOptions& o, double tolerance,
                    int window, int iterations, std::vector<double>& history, int& used) {
  const int nb = static_cast<int>(start.beams.size());
  const int m = kBeamParameters * nb;
  const double h = 1.0 / P.n();
  // Work in voxel-sized units: a unit change of any scaled parameter moves
  // the beam's surface by about one voxel, so one step length suits all.
  VecX scale(m);
  for (int i = 0; i < nb; ++i) {
    const Beam& b = start.beams[i];
    scale.segment<8>(kBeamParameters * i).setConstant(h);
    scale[kBeamParameters * i + 8] = h / std::max({b.r0, b.r1, h});
  }
  auto beam_of = [&](const VecX& x, int i) {
    const auto p = x.segment<kBeamParameters>(kBeamParameters * i);
    Beam b;
    b.a = p.segment<3>(0), b.b = p.segment<3>(3);
    return sized(b, p[6], p[7], p[8]);
  };
  auto occupancies = [&](const VecX& x) {
    std::vector<std::vector<double>> d;
    for (int i = 0; i < nb; ++i) d.push_back(P.occupancy(beam_of(x, i), start.caps));
    return d;
  };
  auto combined = [&](const std::vector<std::vector<double>>& d, int skip) {
    std::vector<double> out = P.empty();
    for (int i = 0; i < nb; ++i)
      if (i != skip) take_max(out, d[i]);
    return out;
  };
  auto clamp_sizes = [&](VecX& x) {
    for (int i = 0; i < nb; ++i)
      for (int j : {6, 7}) x[kBeamParameters * i + j] = std::max(x[kBeamParameters * i + j], 0.0);
  };

  VecX x = template_parameters(start);
  clamp_sizes(x);
  std::vector<std::vector<double>> d = occupancies(x);
  double value = P.objective(combined(d, -1));
  history.push_back(value);
  if (m == 0) return start;
  // Central differences of each beam's occupancy, chained with the
  // objective's exact first-order response (FitProblem::sensitivity); the
  // objective's own central difference differs from this by O(step^2).
  auto gradient = [&](double dz) {
    const std::vector<double> weight = P.sensitivity(combined(d, -1));
    VecX g(m);
    for (int i = 0; i < nb; ++i) {
      // Only beam i changes while its parameters are probed.
      const std::vector<double> others = combined(d, i);
      for (int j = 0; j < kBeamParameters; ++j) {
        const int k = kBeamParameters * i + j;
        std::vector<double> occ[2];
        for (int s = 0; s < 2; ++s) {
          VecX y = x;
          y[k] += (s ? -dz : dz) * scale[k];
          occ[s] = P.occupancy(beam_of(y, i), start.caps);
        }
        double change = 0;
        for (std::size_t f = 0; f < weight.size(); ++f)
          change += weight[f] * (std::max(others[f], occ[0][f]) - std::max(others[f], occ[1][f]));
        g[k] = change / (2 * dz);
      }
    }
    return g;
  };

  double dz = o.difference_step;
  double alpha = -1;
  VecX last_x, last_g;
  for (int it = 0; it < iterations; ++it) {
    ++used;
    const VecX g = gradient(dz);
    const double largest = g.cwiseAbs().maxCoeff();
    if (!(largest > 0)) break;
    // The first trial step moves the most sensitive parameter by
    // initial_step voxels; later ones take the Barzilai-Borwein length
    // (the curvature seen along the last step), which lets plain gradient
    // steps cope with ends and sizes of very different stiffness. At most
    // four voxels either way; backtracking keeps every step a descent.
    if (alpha < 0) {
      alpha = o.initial_step / largest;
    } else {
      const VecX s = (x - last_x).cwiseQuotient(scale), y = g - last_g;
      alpha = s.dot(y) > 0 ? s.squaredNorm() / s.dot(y) : 2 * alpha;
    }
    alpha = std::min(alpha, 4.0 / largest);
    bool accepted = false;
    VecX trial;
    std::vector<std::vector<double>> trial_d;
    double trial_value = value;
    for (int tries = 0; tries < 30 && !accepted; ++tries) {
      trial = x - alpha * g.cwiseProduct(scale);
      clamp_sizes(trial);
      trial_d = occupancies(trial);
      trial_value = P.objective(combined(trial_d, -1));
      if (trial_value <= value - 1e-4 * alpha * g.squaredNorm())
        accepted = true;
      else
        alpha *= 0.5;
    }
    if (!accepted) {
      // Near a kink of the objective (a dome switching sides, images
      // meeting) a wide difference misjudges the slope: narrow it before
      // giving up.
      if (dz <= o.difference_step / 8) break;
      dz *= 0.5;
      alpha = -1;
      continue;
    }
    last_x = x, last_g = g;
    x = trial, d = std::move(trial_d), value = trial_value;
    history.push_back(value);
    const std::size_t k = history.size();
    if (k > std::size_t(window) && history[k - 1 - window] - value <= tolerance * value) break;
  }
  BeamTemplate out = start;
  for (int i = 0; i < nb; ++i) out.beams[i] = beam_of(x, i);
  return out;
}

// The model sharpens in stages, each refining the last one's result. The
// one-voxel kernel (sharpening 1) stands for a voxel's partial volume and
// gives the objective a basin as wide as a voxel, but a voxel whose centre
// lies just inside a thin beam is solid in the target while the beam fills
// little of it: near junctions and thin beams the best partial-volume fit
// misses the target in several percent of voxels. The sharper kernels
// approach the point sampling of rasterize_template, where the template
// that drew a cell fits it exactly. Earlier stages only have to bring the
// beams near their place and stop at a looser tolerance, judged over a few
// steps: one short Barzilai-Borwein step says little about progress.
struct Stage {
  double sharpening, tolerance_factor;
  int window;
};
constexpr Stage kStages[] = {{1, 1000, 5}, {2, 100, 5}, {kFitSharpening, 1, 1}};
constexpr int kStageCount = static_cast<int>(std::size(kStages));

TemplateFit refine_in_stages(const VoxelGrid& target, const BeamTemplate& start, const TemplateFitOptions& o) {
  TemplateFit fit;
  fit.fitted = start;
  int budget = o.max_iterations;
  for (int s = 0; s < kStageCount; ++s) {
    const FitProblem P(target, o.width, kStages[s].sharpening);
    const bool last = s + 1 == kStageCount;
    // The later stages keep a share of the gradients for themselves.
    const int allowed = last ? budget : budget / (kStageCount - s);
    std::vector<double> history;
    int used = 0;
    fit.fitted = refine(P, fit.fitted, o, kStages[s].tolerance_factor * o.relative_tolerance, kStages[s].window,
                        allowed, history, used);
    budget -= used;
    fit.evaluations += P.evaluations;
    fit.steps += static_cast<int>(history.size()) - 1;
    if (last) fit.objective = std::move(history);
  }
  fit.voxel_difference = voxel_difference(target, fit.fitted);
  return fit;
}

// Restarts from a skeleton's beams. Thinning puts a junction at the
// centroid of its voxels, so a beam often ends where its images meet (a
// cell corner, the body centre, an edge's midpoint) and lies on a mirror
// plane or a rotation axis, mapped onto itself by some symmetries. Moves of
// an end that such a symmetry turns into one another change the objective
// alike, so its slope along them is zero and the descent leaves the point
// only along what small asymmetry the section gives it, often to settle
// beside the true beams where these meet off the point (a body-centred
// lattice whose beams start one or two voxels off the corner). A restart
// moves one end of such a beam kRestartOffset voxels along a coordinate
// axis across it, one axis of each set the symmetries turn into one another.
constexpr double kRestartOffset = 1.5;      // voxels
constexpr double kSymmetryTolerance = 0.5;  // voxels: thinning places a junction to within half a voxel

std::vector<BeamTemplate> restart_templates(const BeamTemplate& tpl, int n) {
  std::vector<BeamTemplate> out;
  const double h = 1.0 / n, tol = kSymmetryTolerance * h;
  for (std::size_t i = 0; i < tpl.beams.size(); ++i) {
    const Beam& beam = tpl.beams[i];
    const Vec3 axis = beam.b - beam.a;
    if (!(axis.norm() > 1e-12)) continue;
    // Symmetries that map the beam's axis onto itself, both ends kept or
    // the two swapped.
    std::vector<Mat3> keeping;
    bool swapping = false;
    for (const Mat3& S : cell_symmetries()) {
      const Vec3 a = apply_cell_symmetry(S, beam.a), b = apply_cell_symmetry(S, beam.b);
      Vec3 shift = (beam.a - a).array().round().matrix();
      if ((a + shift - beam.a).norm() <= tol && (b + shift - beam.b).norm() <= tol) keeping.push_back(S);
      shift = (beam.b - a).array().round().matrix();
      if ((a + shift - beam.b).norm() <= tol && (b + shift - beam.a).norm() <= tol) swapping = true;
    }
    if (keeping.size() < 2) continue;  // only the identity
    std::vector<Vec3> moves;
    for (int d = 0; d < 6; ++d) {
      Vec3 e = Vec3::Zero();
      e[d / 2] = d % 2 ? -1.0 : 1.0;
      if (std::abs(e.dot(axis.normalized())) > 0.9) continue;  // along the beam: the descent sees that move
      bool seen = false;
      for (const Vec3& m : moves)
        for (const Mat3& S : keeping) seen = seen || (S * m - e).norm() < 1e-9;
      if (!seen) moves.push_back(e);
    }
    // A symmetry that swaps the ends makes the moves of one end those of the other.
    for (int end = 0; end < (swapping ? 1 : 2); ++end)
      for (const Vec3& e : moves) {
        BeamTemplate moved = tpl;
        (end ? moved.beams[i].b : moved.beams[i].a) += kRestartOffset * h * e;
        out.push_back(moved);
      }
  }
  return out;
}

}  // namespace

std::vector<double> smooth_cell(const VoxelGrid& cell, double width) {
  check_target(cell, "smooth_cell");
  std::vector<double> solid(cell.size());
  for (std::size_t v = 0; v < solid.size(); ++v) solid[v] = cell.ids[v] != 0;
  return periodic_blur(solid, cell.nx, width);
}

double template_objective(const VoxelGrid& target, const BeamTemplate& tpl, double width) {
  check_target(target, "template_objective");
  const FitProblem P(target, width, kFitSharpening);
  std::vector<double> d = P.empty();
  for (const Beam& b : tpl.beams) take_max(d, P.occupancy(b, tpl.caps));
  return P.objective(d);
}

double voxel_difference(const VoxelGrid& target, const BeamTemplate& tpl) {
  check_target(target, "voxel_difference");
  const VoxelGrid model = rasterize_template(tpl, target.nx);
  std::size_t differ = 0;
  for (std::size_t v = 0; v < model.size(); ++v) differ += (model.ids[v] != 0) != (target.ids[v] != 0);
  return double(differ) / double(model.size());
}

BeamTemplate initialize_sections(const VoxelGrid& target, const BeamTemplate& start,
                                 const TemplateFitOptions& options) {
  check_target(target, "initialize_sections");
  check_options(options, "initialize_sections");
  check_template(start, "initialize_sections");
  const FitProblem P(target, options.width, 1.0);
  BeamTemplate out = start;
  for (Beam& b : out.beams) b = search_section(P, b, out.caps);
  return out;
}

TemplateFit refine_template(const VoxelGrid& target, const BeamTemplate& start, const TemplateFitOptions& options) {
  check_target(target, "refine_template");
  check_options(options, "refine_template");
  check_template(start, "refine_template");
  return refine_in_stages(target, start, options);
}

TemplateFit fit_template(const VoxelGrid& target, const TemplateFitOptions& options) {
  check_target(target, "fit_template");
  check_options(options, "fit_template");
  const std::vector<Segment> segments =
      fundamental_segments(skeleton_segments(target, options.skeleton), options.merge_tolerance);
  if (segments.empty()) throw InputError("fit_template: the target's skeleton has no segments to place beams on");
  BeamTemplate tpl;
  tpl.caps = options.caps;
  for (const Segment& whole : segments) {
    const Segment s = cut_at_mirrors(whole, options.merge_tolerance);
    Beam b;
    b.a = s.a, b.b = s.b;
    tpl.beams.push_back(b);
  }
  const FitProblem P(target, options.width, 1.0);
  for (Beam& b : tpl.beams) b = search_section(P, b, tpl.caps);
  TemplateFit fit = refine_in_stages(target, tpl, options);
  fit.evaluations += P.evaluations;
  if (fit.voxel_difference <= options.restart_difference) return fit;
  const std::vector<BeamTemplate> restarts = restart_templates(tpl, target.nx);
  for (std::size_t r = 0; r < restarts.size() && int(r) < options.max_restarts; ++r) {
    TemplateFit other = refine_in_stages(target, restarts[r], options);
    const int evaluations = fit.evaluations + other.evaluations, steps = fit.steps + other.steps;
    // The objective decides, as it is what the fit minimizes.
    if (other.objective.back() < fit.objective.back()) fit = std::move(other);
    fit.evaluations = evaluations, fit.steps = steps;
    if (fit.voxel_difference <= options.restart_difference) break;
  }
  return fit;
}

}  // namespace msfab
