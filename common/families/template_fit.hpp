#pragma once
// Fitting a beam template to a microstructure (thesis §3.3.1, Fig. 3-5):
// one beam per skeleton segment of the fundamental domain (a segment that
// is its own mirror image cut to the part that rebuilds it), each beam's
// cross-section (r0, r1, theta) initialized on its own by a small search,
// then all parameters, ends included, refined together by gradient descent
// with central differences and a backtracking step.
//
// The objective is the mean over the cell of the squared difference
// between the template's smooth rasterization (rasterize_template_smooth)
// and the target blurred by the same Gaussian. The descent runs in stages
// that sharpen the smooth rasterization from partial volumes (sharpening
// 1, a wide and smooth basin) towards the point sampling of
// rasterize_template (kFitSharpening), so that the template that drew a
// cell is where the objective ends up. A fit from a skeleton whose result
// still differs from the target restarts from the skeleton's beams with
// ends moved off symmetric points, where the descent cannot tell which way
// to leave them, and keeps the lowest objective.
#include <vector>

#include "families/beam_template.hpp"
#include "families/skeleton.hpp"

namespace msfab {

// The sharpening (beam_occupancy) of the fit's last stage and of
// template_objective.
inline constexpr double kFitSharpening = 4.0;

struct TemplateFitOptions {
  double width = 1.0;                // voxels: Gaussian sigma of the target, blur of the template
  int max_iterations = 200;          // gradients computed, at most, over all stages of one descent
  double relative_tolerance = 1e-6;  // stop when a step lowers the objective by less than this fraction
                                     // (the earlier stages: 1000x and 100x this, by their last five steps)
  double difference_step =
      0.25;  // central-difference step, voxels (theta: the angle that moves the section corner that far)
  double initial_step = 1.0;         // voxels: the first trial step's largest parameter change
  SkeletonOptions skeleton;          // segments for fit_template
  double merge_tolerance = 0.05;     // fundamental_segments
  bool caps = true;                  // the template fit_template builds
  double restart_difference = 0.01;  // fit_template restarts while its voxel difference is above this
  int max_restarts = 4;              // fit_template: restarts tried, at most
};

struct TemplateFit {
  BeamTemplate fitted;
  // The objective (template_objective) before the last stage's first step,
  // then after each of its accepted steps (non-increasing).
  std::vector<double> objective;
  double voxel_difference = 0;  // fraction of voxels where rasterize_template(fitted) differs from the target
  int evaluations = 0;          // objective evaluations
  int steps = 0;                // accepted steps, all stages and restarts
};

// The whole pipeline from a target cell (cubic n x n x n, n >= 3, any
// non-zero id solid): skeleton segments of the fundamental domain, cut at
// mirror planes (cut_at_mirrors, merge_tolerance), one beam each, sections
// initialized, then refined; while the voxel difference is above
// restart_difference, refined again from the next restart (see
// template_fit.cpp, at most max_restarts), keeping the fit with the lowest
// objective. InputError for a bad cell or bad options, or a cell whose
// skeleton has no segments (no template).
TemplateFit fit_template(const VoxelGrid& target, const TemplateFitOptions& options = {});

// Refinement only, from a given template (a family's template fitted to
// each member of the family). An empty template is returned unchanged.
TemplateFit refine_template(const VoxelGrid& target, const BeamTemplate& start, const TemplateFitOptions& options = {});

// The cross-section search of every beam, each beam on its own against the
// target: sizes and angle that minimize the objective of that beam alone.
BeamTemplate initialize_sections(const VoxelGrid& target, const BeamTemplate& start,
                                 const TemplateFitOptions& options = {});

// The fit objective of a template against a target: that of the last
// stage, with the model at kFitSharpening.
double template_objective(const VoxelGrid& target, const BeamTemplate& tpl, double width = 1.0);

// Fraction of voxels where the template's binary rasterization at the
// target's resolution differs from the target.
double voxel_difference(const VoxelGrid& target, const BeamTemplate& tpl);

// The target blurred by a periodic Gaussian of standard deviation `width`
// voxels (x fastest), what the smooth template is compared with.
std::vector<double> smooth_cell(const VoxelGrid& cell, double width);

}  // namespace msfab
