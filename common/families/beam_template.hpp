#pragma once
// Microstructure templates (thesis §3.3.1 and Appendix A): cuboid beams in
// the unit cell, mirrored by the 48 symmetries of the cube about the cell
// centre and repeated periodically. The parameters of a template are what
// the fit adjusts and what principal component regression works on.
#include <string>
#include <vector>

#include "core/types.hpp"
#include "families/cell_symmetry.hpp"
#include "fem/voxel_grid.hpp"

namespace msfab {

// A cuboid from a to b (unit-cell coordinates) with a rectangular cross
// section of half-sizes r0 (along the section's y) and r1 (along its z),
// turned by theta (radians) about the axis.
struct Beam {
  Vec3 a = Vec3::Zero(), b = Vec3::Zero();
  double r0 = 0, r1 = 0, theta = 0;
};

// caps: each end of each beam carries a dome, the part of the cross-section
// prism within r_min = min(r0 + r1 / 20, r0 / 20 + r1) of the end point,
// which rounds off the joints between beams.
struct BeamTemplate {
  std::vector<Beam> beams;
  bool caps = true;
};

// The section frame of Appendix A: x along the axis; y the global y axis
// made normal to x (the global x axis when |x_y| > 0.9); z = x cross y;
// then y and z turned by theta about x.
struct BeamFrame {
  Vec3 x = Vec3::UnitX(), y = Vec3::UnitY(), z = Vec3::UnitZ();
  double length = 0;
};
BeamFrame beam_frame(const Beam& beam);

// Signed distance from p to the beam alone (no symmetry, no periodicity),
// negative inside. Exact for a cuboid without caps; with caps, exact
// inside each of cuboid and domes and a lower bound outside near a dome.
// A point is inside (distance <= 0) exactly when Appendix A's drawCuboid
// fills it. A beam shorter than 1e-10 is empty (+infinity).
double beam_signed_distance(const Beam& beam, bool caps, const Vec3& p);

// The smallest signed distance, over the beam's images under the cube
// symmetries and the lattice translations, at the centre of each
// fundamental voxel; values above `cutoff` (unit-cell units, > 0) come
// back as `cutoff`, which lets distant images be skipped.
std::vector<double> beam_distance(const Beam& beam, bool caps, const FundamentalVoxels& voxels, double cutoff);

// The beam's share of each fundamental voxel, the largest over its
// images: a smooth stand-in for the voxel's partial volume. The cuboid is
// convolved with a kernel that factors along its section frame into
// logistic densities with the variance of a one-voxel box (scale
// h / (2 pi)), so the occupancy is exactly the product of three smoothed
// intervals and a beam's material is counted without bias even when it is
// only a few voxels thick. A dome is smoothed as if the end moved out by
// the dome's height at the point's section position. `sharpening` (>= 1,
// else InputError) divides the kernel's scale: the occupancy then tends to
// whether the voxel's centre lies in the beam, what rasterize_template
// samples. Material more than 4 pi kernel scales away is not counted.
std::vector<double> beam_occupancy(const Beam& beam, bool caps, const FundamentalVoxels& voxels,
                                   double sharpening = 1.0);

// A periodic n^3 field (x fastest) convolved with a Gaussian of standard
// deviation `width` voxels, truncated at 3 widths and renormalized.
// InputError for a field of the wrong size or width <= 0.
std::vector<double> periodic_blur(const std::vector<double>& field, int n, double width);

// The template at resolution n: a voxel is solid (id 1) when its centre
// lies in some beam or in an image of it under the cube symmetries and the
// lattice translations. Computed on the fundamental domain and mirrored,
// so the cell is exactly cubic-symmetric. voxel_size = 1 / n. InputError
// for n < 1 or a beam with a negative or non-finite size or end.
VoxelGrid rasterize_template(const BeamTemplate& tpl, int n);

// The same as occupancies in [0, 1] (x fastest): the largest
// beam_occupancy (at `sharpening`) over the beams, then periodic_blur by
// `width` voxels, the blur the fit applies to the target. Beams are united
// before the blur, at one voxel's sharpness or sharper, so where images
// meet or beams cross their material counts once; a sigmoid of the signed
// distance as wide as the blur would instead ignore a thin beam's far face
// and overstate its material.
std::vector<double> rasterize_template_smooth(const BeamTemplate& tpl, int n, double width = 1.0,
                                              double sharpening = 1.0);

// InputError, naming `context`, the beam and the field, for an end point
// that is not finite or a size that is negative or not finite.
void check_template(const BeamTemplate& tpl, const std::string& context);

// Flat parameters: 9 per beam, beam after beam: a (3), b (3), r0, r1,
// theta. (Appendix A's parameter files order all ends first, then all
// sections; convert when reading those.)
inline constexpr int kBeamParameters = 9;
VecX template_parameters(const BeamTemplate& tpl);
// InputError when the size is not a multiple of 9.
BeamTemplate template_from_parameters(const VecX& parameters, bool caps);

}  // namespace msfab
