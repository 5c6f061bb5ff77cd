// Microstructure templates: skeleton by thinning, path simplification,
// beam rasterization, and fitting a template to a structure.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "core/errors.hpp"
#include "families/beam_template.hpp"
#include "families/skeleton.hpp"
#include "families/template_fit.hpp"
#include "gamut/structure_ops.hpp"

namespace msfab {
namespace {

VoxelGrid empty_cell(int n) { return VoxelGrid(n, n, n, 1.0 / n, 0); }

std::size_t solid_count(const VoxelGrid& c) {
  std::size_t count = 0;
  for (int id : c.ids) count += id != 0;
  return count;
}

// Edges minus vertices plus pieces: the number of independent cycles.
int cycle_rank(const SkeletonGraph& g) {
  int edges = 0;
  for (const auto& nb : g.neighbours) edges += static_cast<int>(nb.size());
  edges /= 2;
  std::vector<int> piece(g.voxel.size(), -1);
  int pieces = 0;
  for (std::size_t s = 0; s < g.voxel.size(); ++s) {
    if (piece[s] >= 0) continue;
    std::vector<int> stack{int(s)};
    piece[s] = pieces;
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      for (int w : g.neighbours[v])
        if (piece[w] < 0) piece[w] = pieces, stack.push_back(w);
    }
    ++pieces;
  }
  return edges - static_cast<int>(g.voxel.size()) + pieces;
}

// Random blobs: random seeds grown by a 26-neighbour majority filter.
VoxelGrid blobby_cell(int n, double density, unsigned seed) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution coin(density);
  VoxelGrid c = empty_cell(n);
  for (int& id : c.ids) id = coin(rng);
  VoxelGrid out = c;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        int count = 0;
        for (int dz = -1; dz <= 1; ++dz)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) count += c.at((i + dx + n) % n, (j + dy + n) % n, (k + dz + n) % n);
        out.at(i, j, k) = count >= 13;
      }
  return out;
}

TEST(FamiliesSkeleton, StraightPeriodicBarThinsToItsCentreLine) {
  const int n = 12;
  VoxelGrid c = empty_cell(n);
  for (int k = 4; k <= 6; ++k)
    for (int j = 4; j <= 6; ++j)
      for (int i = 0; i < n; ++i) c.at(i, j, k) = 1;
  const VoxelGrid s = thin_cell(c);
  EXPECT_EQ(solid_count(s), std::size_t(n));
  for (int i = 0; i < n; ++i) EXPECT_EQ(s.at(i, 5, 5), 1) << "x = " << i;
  // Its graph is one loop around the cell, and it simplifies to one segment
  // of length 1 along x.
  EXPECT_EQ(cycle_rank(skeleton_graph(s)), 1);
  const auto segments = skeleton_segments(c);
  ASSERT_EQ(segments.size(), 1u);
  const Vec3 d = segments[0].b - segments[0].a;
  EXPECT_NEAR(std::abs(d.x()), 1.0, 1e-12);
  EXPECT_NEAR(d.y(), 0.0, 1e-12);
  EXPECT_NEAR(d.z(), 0.0, 1e-12);
  EXPECT_NEAR(segments[0].a.y(), 5.5 / n, 1e-12);
}

TEST(FamiliesSkeleton, ThinningKeepsPiecesAndCavitiesAndIsThin) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    const VoxelGrid c = blobby_cell(16, 0.45, seed);
    const VoxelGrid s = thin_cell(c);
    const int solid = count_solid_components(c), holes = count_void_components(c);
    EXPECT_EQ(count_solid_components(s), solid) << "seed " << seed;
    EXPECT_EQ(count_void_components(s), holes) << "seed " << seed;
    // The skeleton lies inside the solid and thinning it again removes nothing.
    for (std::size_t v = 0; v < c.size(); ++v)
      if (s.ids[v]) {
        ASSERT_NE(c.ids[v], 0);
      }
    EXPECT_EQ(thin_cell(s).ids, s.ids) << "seed " << seed;
    EXPECT_LT(solid_count(s), solid_count(c) / 4) << "seed " << seed;
    std::printf("[ measured ] seed %u: %zu solid -> %zu skeleton voxels, %d solid pieces, %d void pieces\n", seed,
                solid_count(c), solid_count(s), solid, holes);
  }
}

TEST(FamiliesSkeleton, SquareFrameKeepsItsLoop) {
  const int n = 16;
  VoxelGrid c = empty_cell(n);
  for (int k = 6; k <= 8; ++k)
    for (int j = 2; j <= 13; ++j)
      for (int i = 2; i <= 13; ++i)
        if (i <= 4 || i >= 11 || j <= 4 || j >= 11) c.at(i, j, k) = 1;
  const VoxelGrid s = thin_cell(c);
  EXPECT_EQ(count_solid_components(s), 1);
  const SkeletonGraph g = skeleton_graph(s);
  EXPECT_EQ(cycle_rank(g), 1);
  const auto paths = skeleton_paths(g);
  ASSERT_EQ(paths.size(), 1u);
  EXPECT_TRUE(paths[0].closed);
  EXPECT_NEAR((paths[0].points.front() - paths[0].points.back()).norm(), 0.0, 1e-12);
  // A square loop simplifies to its four corners (five points, closed)
  // once the tolerance passes the corners' rounding by thinning.
  EXPECT_EQ(simplify_polyline(paths[0].points, 1.5 / n).size(), 5u);
  const auto kept = simplify_polyline(paths[0].points, 0.02);
  std::printf("[ measured ] square frame: %zu loop voxels, %zu points kept at 0.02\n", paths[0].points.size() - 1,
              kept.size());
  EXPECT_GE(kept.size(), 5u);
  EXPECT_LE(kept.size(), 9u);
  // A solid block with the same outline has no loop.
  VoxelGrid block = empty_cell(n);
  for (int k = 6; k <= 8; ++k)
    for (int j = 2; j <= 13; ++j)
      for (int i = 2; i <= 13; ++i) block.at(i, j, k) = 1;
  EXPECT_EQ(cycle_rank(skeleton_graph(thin_cell(block))), 0);
}

TEST(FamiliesSkeleton, PathSimplification) {
  const double h = 1.0 / 32;
  std::vector<Vec3> line, ell, stair;
  for (int i = 0; i < 10; ++i) line.push_back(Vec3(i + 0.5, 3.5, 3.5) * h);
  EXPECT_EQ(simplify_polyline(line, 0.02), (std::vector<int>{0, 9}));
  for (int i = 0; i < 6; ++i) ell.push_back(Vec3(i + 0.5, 0.5, 0.5) * h);
  for (int j = 1; j < 6; ++j) ell.push_back(Vec3(5.5, j + 0.5, 0.5) * h);
  EXPECT_EQ(simplify_polyline(ell, 0.02), (std::vector<int>{0, 5, 10}));
  // A digital line of slope 0.4 strays by less than half a voxel from its
  // chord: one segment at the thesis's 0.02 (0.64 voxels here), but not
  // at a tolerance below that.
  for (int i = 0; i <= 20; ++i) stair.push_back(Vec3(i, std::floor(0.4 * i + 0.5), 0) * h);
  EXPECT_EQ(simplify_polyline(stair, 0.02).size(), 2u);
  EXPECT_GT(simplify_polyline(stair, 0.005).size(), 3u);
  EXPECT_THROW(simplify_polyline({Vec3::Zero()}, 0.02), InputError);
  EXPECT_THROW(simplify_polyline(line, -1), InputError);
}

TEST(FamiliesSkeleton, FundamentalSegmentsDropSymmetricCopies) {
  const Segment A{Vec3(0.1, 0.2, 0.3), Vec3(0.2, 0.25, 0.45)};
  // A mirrored in x about the cell centre, its axes permuted, moved by a
  // lattice vector and reversed: the same orbit.
  const Segment copy{Vec3(0.25, 0.45, 0.8) + Vec3(-1, 0, 1), Vec3(0.2, 0.3, 0.9) + Vec3(-1, 0, 1)};
  const Segment part{A.a + 0.5 * (A.b - A.a) + Vec3(0.004, 0, 0), A.b};  // a piece of A, 0.004 off
  const Segment other{Vec3(0.1, 0.2, 0.3), Vec3(0.3, 0.2, 0.3)};
  const auto kept = fundamental_segments({part, A, copy, other}, 0.01);
  ASSERT_EQ(kept.size(), 2u);
  // Longest first; each is the image with its midpoint in the domain.
  EXPECT_NEAR((kept[0].b - kept[0].a).norm(), 0.2, 1e-12);
  EXPECT_NEAR((kept[1].b - kept[1].a).norm(), (A.b - A.a).norm(), 1e-12);
  for (const Segment& k : kept) {
    const Vec3 m = 0.5 * (k.a + k.b);
    EXPECT_TRUE(m.x() >= 0 && m.x() <= m.y() && m.y() <= m.z() && m.z() <= 0.5) << m.transpose();
  }
  EXPECT_EQ(fundamental_segments({part, A, copy, other}, 0.001).size(), 3u);  // the piece is 0.004 off
  EXPECT_THROW(fundamental_segments({A}, -1), InputError);
}

TEST(FamiliesSkeleton, FundamentalSegmentsOfASymmetricFrame) {
  // The periodic cube frame (bars along every cell edge) is one orbit of
  // segments; with the body diagonals added, two.
  BeamTemplate frame;
  frame.caps = false;
  frame.beams.push_back({Vec3(0, 0, 0), Vec3(0.5, 0, 0), 0.07, 0.07, 0});
  const int n = 24;
  const auto one = fundamental_segments(skeleton_segments(rasterize_template(frame, n)));
  ASSERT_EQ(one.size(), 1u);
  for (const Vec3& p : {one[0].a, one[0].b})
    std::printf("[ measured ] frame segment end (%.4f %.4f %.4f)\n", p.x(), p.y(), p.z());
  EXPECT_NEAR((one[0].b - one[0].a).norm(), 1.0, 0.5 / n);
  frame.beams.push_back({Vec3(0, 0, 0), Vec3(0.5, 0.5, 0.5), 0.05, 0.05, 0});
  const auto all = skeleton_segments(rasterize_template(frame, n));
  const auto two = fundamental_segments(all);
  std::printf("[ measured ] frame + diagonals: %zu skeleton segments, %zu in the fundamental domain\n", all.size(),
              two.size());
  EXPECT_EQ(two.size(), 2u);
  for (const Segment& s : two) {
    const Vec3 m = 0.5 * (s.a + s.b);
    const double eps = 1e-12;
    EXPECT_TRUE(m.x() >= -eps && m.x() <= m.y() + eps && m.y() <= m.z() + eps && m.z() <= 0.5 + eps);
  }
}

TEST(FamiliesSkeleton, CutAtMirrorsKeepsThePartThatRebuildsTheSegment) {
  // A whole edge of a cube frame, as thinning leaves it: half a voxel of
  // n = 24 off the edge, a closed loop through the cell. The mirror plane
  // z = 1/2 maps the part beyond it onto the part before it.
  const double off = 0.5 / 24;
  const Segment edge{Vec3(off, off, -off), Vec3(off, off, 1 - off)};
  const Segment half = cut_at_mirrors(edge);
  std::printf("[ measured ] frame edge cut to (%.4f %.4f %.4f)-(%.4f %.4f %.4f)\n", half.a.x(), half.a.y(), half.a.z(),
              half.b.x(), half.b.y(), half.b.z());
  EXPECT_NEAR(std::abs(half.b.z() - half.a.z()), 0.5 + off, 1e-12);
  EXPECT_NEAR(std::max(half.a.z(), half.b.z()), 0.5, 1e-12);
  for (const Vec3& p : {half.a, half.b}) {
    EXPECT_NEAR(p.x(), off, 1e-12);
    EXPECT_NEAR(p.y(), off, 1e-12);
  }
  // A bar from a corner to the body centre is no image of itself, nor is a
  // bar that crosses a mirror plane obliquely or one in general position.
  const Segment others[] = {{Vec3(0, 0, 0), Vec3(0.5, 0.5, 0.5)},
                            {Vec3(0.4, 0.2, 0.2), Vec3(0.6, 0.3, 0.3)},
                            {Vec3(0.083, 0.201, 0.337), Vec3(0.167, 0.299, 0.413)}};
  for (const Segment& s : others) {
    const Segment same = cut_at_mirrors(s);
    EXPECT_EQ(same.a, s.a);
    EXPECT_EQ(same.b, s.b);
  }
  EXPECT_THROW(cut_at_mirrors(edge, -1), InputError);
}

// A beam about the centroid of the fundamental tetrahedron, in general
// position, clear of its 47 images (some would touch it were its section
// one voxel of n = 32 wider on each side).
Beam general_beam() { return {Vec3(0.083, 0.201, 0.337), Vec3(0.167, 0.299, 0.413), 0.03, 0.05, 0.4}; }

TEST(FamiliesTemplate, RasterizationIsCubicSymmetricAndMatchesTheBeam) {
  BeamTemplate t;
  t.beams.push_back({Vec3(0.13, 0.71, 0.38), Vec3(0.92, 0.27, 1.15), 0.04, 0.07, 0.7});  // crosses the cell boundary
  t.beams.push_back(general_beam());
  for (int n : {17, 32}) {
    const VoxelGrid c = rasterize_template(t, n);
    EXPECT_TRUE(has_cubic_symmetry(c)) << "n = " << n;
    const std::size_t solid = solid_count(c);
    EXPECT_GT(solid, 0u);
    EXPECT_LT(solid, c.size());
    if (n != 17) continue;
    // Solid exactly where some image of a beam holds the voxel centre: the
    // distance to an image is the distance from the inverse image of the
    // point to the beam itself.
    int mismatches = 0;
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          const Vec3 p((i + 0.5) / n, (j + 0.5) / n, (k + 0.5) / n);
          bool inside = false;
          for (const Mat3& S : cell_symmetries()) {
            const Vec3 q = apply_cell_symmetry(S.transpose(), p);
            for (int l = 0; l < 27 && !inside; ++l) {
              const Vec3 shift(l % 3 - 1, l / 3 % 3 - 1, l / 9 - 1);
              for (const Beam& b : t.beams) inside = inside || beam_signed_distance(b, t.caps, q + shift) <= 0;
            }
          }
          mismatches += inside != (c.at(i, j, k) == 1);
        }
    EXPECT_EQ(mismatches, 0) << "n = " << n;
  }
  const int n = 32, f = 4;
  const std::vector<double> s = rasterize_template_smooth(t, n, 1.0);
  VoxelGrid q = empty_cell(n);
  for (std::size_t v = 0; v < s.size(); ++v) {
    ASSERT_GE(s[v], 0.0);
    ASSERT_LE(s[v], 1.0);
    q.ids[v] = static_cast<int>(std::lround(1000 * s[v]));
  }
  EXPECT_TRUE(has_cubic_symmetry(q));
  // The smooth cell is the binary cell blurred: compare with blurring a
  // rasterization f times finer and sampling it at the coarse voxel centres.
  const VoxelGrid fine = rasterize_template(t, f * n);
  const std::vector<double> blurred = smooth_cell(fine, 1.0 * f);
  double worst = 0, rms = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        // Coarse centre (i + 1/2) / n lies between fine voxels f i + f/2 - 1 and f i + f/2.
        double avg = 0;
        const int o = f / 2 - 1;
        for (int c = 0; c < 8; ++c)
          avg += blurred[fine.index(f * i + o + (c & 1), f * j + o + (c >> 1 & 1), f * k + o + (c >> 2))] / 8;
        const double e = s[q.index(i, j, k)] - avg;
        worst = std::max(worst, std::abs(e));
        rms += e * e / s.size();
      }
  std::printf("[ measured ] smooth vs blurred fine cell: max %.3f rms %.4f\n", worst, std::sqrt(rms));
  EXPECT_LT(std::sqrt(rms), 0.025);
  EXPECT_LT(worst, 0.1);
}

TEST(FamiliesTemplate, BeamGeometryFollowsTheSectionFrame) {
  // A beam along x: section y = global y turned by theta.
  const Beam b{Vec3(0.2, 0.5, 0.5), Vec3(0.6, 0.5, 0.5), 0.05, 0.1, 0.5};
  const BeamFrame f = beam_frame(b);
  EXPECT_NEAR(f.length, 0.4, 1e-15);
  EXPECT_NEAR((f.y - Vec3(0, std::cos(0.5), std::sin(0.5))).norm(), 0, 1e-12);
  EXPECT_NEAR(f.x.cross(f.y).dot(f.z), 1.0, 1e-12);
  const Vec3 mid(0.4, 0.5, 0.5);
  EXPECT_NEAR(beam_signed_distance(b, false, mid), -0.05, 1e-12);
  EXPECT_NEAR(beam_signed_distance(b, false, mid + 0.08 * f.y), 0.03, 1e-12);
  EXPECT_NEAR(beam_signed_distance(b, false, mid + 0.08 * f.z), -0.02, 1e-12);
  // Beyond the end: no cap, flat; with a cap, the dome reaches r_min.
  const double rmin = std::min(0.05 + 0.005, 0.0025 + 0.1);
  EXPECT_NEAR(beam_signed_distance(b, false, Vec3(0.63, 0.5, 0.5)), 0.03, 1e-12);
  EXPECT_LT(beam_signed_distance(b, true, Vec3(0.6 + rmin - 1e-6, 0.5, 0.5)), 0);
  EXPECT_GT(beam_signed_distance(b, true, Vec3(0.6 + rmin + 1e-6, 0.5, 0.5)), 0);
  // An axis close to y takes global x as its reference.
  const BeamFrame up = beam_frame({Vec3(0, 0, 0), Vec3(0.1, 1, 0), 0.1, 0.1, 0});
  EXPECT_NEAR(std::abs(up.y.dot(up.x)), 0.0, 1e-12);
  EXPECT_GT(std::abs(up.y.x()), 0.9);
}

TEST(FamiliesTemplate, SharpenedOccupancyTendsToThePointSampling) {
  // Sharpened, the occupancy says whether a voxel's centre lies in the
  // beam, as rasterize_template samples it; unsharpened, a thin beam fills
  // the voxels along its faces only in part.
  const Beam b = general_beam();
  const int n = 16;
  const FundamentalVoxels fv = fundamental_voxels(n);
  const std::vector<double> distance = beam_distance(b, true, fv, 1.0);
  const std::vector<double> sharp = beam_occupancy(b, true, fv, 64), soft = beam_occupancy(b, true, fv);
  double worst_sharp = 0, worst_soft = 0;
  int clear = 0;
  for (std::size_t v = 0; v < fv.voxel.size(); ++v) {
    if (std::abs(distance[v]) < 0.1 / n) continue;  // the centre on the surface, give or take
    ++clear;
    const double solid = distance[v] <= 0;
    worst_sharp = std::max(worst_sharp, std::abs(sharp[v] - solid));
    worst_soft = std::max(worst_soft, std::abs(soft[v] - solid));
  }
  std::printf("[ measured ] %d voxels clear of the surface: sharpened %.2g, unsharpened %.2f from the point sampling\n",
              clear, worst_sharp, worst_soft);
  EXPECT_GT(clear, 100);
  EXPECT_LT(worst_sharp, 1e-6);
  EXPECT_GT(worst_soft, 0.2);
  EXPECT_THROW(beam_occupancy(b, true, fv, 0.5), InputError);
}

TEST(FamiliesTemplate, SolidFractionConvergesUnderRefinement) {
  BeamTemplate t;
  t.beams.push_back({Vec3(0.13, 0.71, 0.38), Vec3(0.92, 0.27, 1.15), 0.04, 0.07, 0.7});
  t.beams.push_back(general_beam());
  auto fraction = [&](int n) { return double(solid_count(rasterize_template(t, n))) / std::pow(n, 3); };
  const double f16 = fraction(16), f32 = fraction(32), f64 = fraction(64), f128 = fraction(128);
  std::printf("[ measured ] solid fraction n=16 %.5f  n=32 %.5f  n=64 %.5f  n=128 %.5f\n", f16, f32, f64, f128);
  EXPECT_LT(std::abs(f64 - f128), std::abs(f32 - f128));
  EXPECT_LT(std::abs(f32 - f128), std::abs(f16 - f128));
  EXPECT_LT(std::abs(f64 - f128), 0.005);
}

TEST(FamiliesTemplate, ParametersRoundTrip) {
  BeamTemplate t;
  t.caps = false;
  t.beams.push_back(general_beam());
  t.beams.push_back({Vec3(1, 2, 3), Vec3(4, 5, 6), 7, 8, 9});
  const VecX x = template_parameters(t);
  ASSERT_EQ(x.size(), 18);
  EXPECT_EQ(x[9], 1);
  EXPECT_EQ(x[17], 9);
  EXPECT_EQ(x[6], 0.03);
  const BeamTemplate u = template_from_parameters(x, false);
  EXPECT_EQ(template_parameters(u), x);
  EXPECT_FALSE(u.caps);
  EXPECT_THROW(template_from_parameters(VecX::Zero(10), true), InputError);
  t.beams[1].r0 = -1;
  EXPECT_THROW(rasterize_template(t, 8), InputError);
  EXPECT_THROW(rasterize_template(BeamTemplate{}, 0), InputError);
  EXPECT_THROW(thin_cell(VoxelGrid(4, 4, 5, 1)), InputError);
}

TEST(FamiliesFit, RecoversAKnownBeamFromPerturbedParameters) {
  const int n = 32;
  const double h = 1.0 / n;
  BeamTemplate truth;
  truth.beams.push_back(general_beam());
  const VoxelGrid target = rasterize_template(truth, n);
  BeamTemplate start = truth;
  Beam& b = start.beams[0];
  b.a += 1.5 * h * Vec3(1, -1, 1).normalized();
  b.b += 1.5 * h * Vec3(-1, -1, 0.5).normalized();
  b.r0 *= 1.3, b.r1 *= 0.7, b.theta += 0.15;
  const TemplateFit fit = refine_template(target, start);
  const Beam& f = fit.fitted.beams[0];
  const Beam& t = truth.beams[0];
  std::printf(
      "[ measured ] one beam: |da| %.3f |db| %.3f voxels, dr0 %.3f dr1 %.3f voxels, dtheta %.3f, "
      "objective %.3g -> %.3g in %zu steps, voxel difference %.4f (start %.4f)\n",
      (f.a - t.a).norm() / h, (f.b - t.b).norm() / h, (f.r0 - t.r0) / h, (f.r1 - t.r1) / h, f.theta - t.theta,
      fit.objective.front(), fit.objective.back(), fit.objective.size() - 1, fit.voxel_difference,
      voxel_difference(target, start));
  EXPECT_LT((f.a - t.a).norm(), h);
  EXPECT_LT((f.b - t.b).norm(), h);
  EXPECT_LT(std::abs(f.r0 - t.r0), h);
  EXPECT_LT(std::abs(f.r1 - t.r1), h);
  EXPECT_LT(fit.voxel_difference, 0.02);
  EXPECT_LT(fit.voxel_difference, voxel_difference(target, start));
  for (std::size_t i = 1; i < fit.objective.size(); ++i) EXPECT_LE(fit.objective[i], fit.objective[i - 1]);
  // Deterministic: the same fit twice gives the same numbers.
  const TemplateFit again = refine_template(target, start);
  EXPECT_EQ(template_parameters(again.fitted), template_parameters(fit.fitted));
  EXPECT_EQ(again.objective, fit.objective);
}

TEST(FamiliesFit, RecoversAJointOfTwoBeams) {
  // Two beams meeting at a joint; the joint end of each is buried in the
  // other beam and only loosely determined, the free ends and the sections
  // are not.
  const int n = 32;
  const double h = 1.0 / n;
  BeamTemplate truth;
  truth.beams.push_back(general_beam());
  truth.beams.push_back({general_beam().b, Vec3(0.07, 0.26, 0.44), 0.035, 0.025, 1.0});
  const VoxelGrid target = rasterize_template(truth, n);
  BeamTemplate start = truth;
  const Vec3 moves[4] = {Vec3(1, -1, 1), Vec3(-1, -1, 0.5), Vec3(0.3, 1, -1), Vec3(-1, 0.2, 0.7)};
  for (int i = 0; i < 2; ++i) {
    Beam& b = start.beams[i];
    b.a += 1.5 * h * moves[2 * i].normalized();
    b.b += 1.5 * h * moves[2 * i + 1].normalized();
    b.r0 *= i ? 0.7 : 1.3;
    b.r1 *= i ? 1.3 : 0.7;
  }
  const TemplateFit fit = refine_template(target, start);
  const Beam &f0 = fit.fitted.beams[0], &f1 = fit.fitted.beams[1];
  const Beam &t0 = truth.beams[0], &t1 = truth.beams[1];
  std::printf(
      "[ measured ] two beams: free ends %.3f %.3f voxels, joint ends %.3f %.3f voxels, "
      "sections %.3f %.3f %.3f %.3f voxels, voxel difference %.4f (start %.4f) in %zu steps\n",
      (f0.a - t0.a).norm() / h, (f1.b - t1.b).norm() / h, (f0.b - t0.b).norm() / h, (f1.a - t1.a).norm() / h,
      (f0.r0 - t0.r0) / h, (f0.r1 - t0.r1) / h, (f1.r0 - t1.r0) / h, (f1.r1 - t1.r1) / h, fit.voxel_difference,
      voxel_difference(target, start), fit.objective.size() - 1);
  EXPECT_LT((f0.a - t0.a).norm(), h);
  EXPECT_LT((f1.b - t1.b).norm(), h);
  EXPECT_LT((f0.b - t0.b).norm(), 2 * h);
  EXPECT_LT((f1.a - t1.a).norm(), 2.5 * h);
  for (double d : {f0.r0 - t0.r0, f0.r1 - t0.r1, f1.r0 - t1.r0, f1.r1 - t1.r1}) EXPECT_LT(std::abs(d), h);
  EXPECT_LT(fit.voxel_difference, 0.02);
  for (std::size_t i = 1; i < fit.objective.size(); ++i) EXPECT_LE(fit.objective[i], fit.objective[i - 1]);
}

TEST(FamiliesFit, SectionSearchFindsTheSizes) {
  const int n = 32;
  const double h = 1.0 / n;
  BeamTemplate truth;
  truth.beams.push_back(general_beam());
  const VoxelGrid target = rasterize_template(truth, n);
  BeamTemplate start = truth;
  start.beams[0].r0 = start.beams[0].r1 = h;
  start.beams[0].theta = 0;
  const Beam b = initialize_sections(target, start).beams[0];
  const Beam& t = truth.beams[0];
  std::printf("[ measured ] section search: r0 %.4f r1 %.4f theta %.3f (truth %.4f %.4f %.3f)\n", b.r0, b.r1, b.theta,
              t.r0, t.r1, t.theta);
  // The section may come out turned by a quarter with its sizes swapped.
  const double small = std::min(b.r0, b.r1), large = std::max(b.r0, b.r1);
  EXPECT_LT(std::abs(small - t.r0), 0.5 * h);
  EXPECT_LT(std::abs(large - t.r1), 0.5 * h);
  EXPECT_LT(template_objective(target, {{b}, true}), template_objective(target, start));
}

TEST(FamiliesFit, SameResultOnOneOrTwoThreads) {
  const int n = 24;
  BeamTemplate truth;
  truth.beams.push_back(general_beam());
  const VoxelGrid target = rasterize_template(truth, n);
  BeamTemplate start = truth;
  start.beams[0].a += Vec3(0.03, 0, 0);
  TemplateFitOptions options;
  options.max_iterations = 10;
  const int threads = omp_get_max_threads();
  // Cells this fine are where thinning, rasterization and blur use threads.
  const VoxelGrid blobs = blobby_cell(48, 0.45, 3);
  omp_set_num_threads(1);
  const TemplateFit one = refine_template(target, start, options);
  const VoxelGrid thin_one = thin_cell(blobs);
  const std::vector<double> smooth_one = rasterize_template_smooth(truth, 128);
  omp_set_num_threads(2);
  const TemplateFit two = refine_template(target, start, options);
  const VoxelGrid thin_two = thin_cell(blobs);
  const std::vector<double> smooth_two = rasterize_template_smooth(truth, 128);
  omp_set_num_threads(threads);
  EXPECT_EQ(template_parameters(one.fitted), template_parameters(two.fitted));
  EXPECT_EQ(one.objective, two.objective);
  EXPECT_EQ(thin_one.ids, thin_two.ids);
  EXPECT_EQ(smooth_one, smooth_two);
}

TEST(FamiliesFit, BadInput) {
  TemplateFitOptions bad;
  bad.width = 0;
  const VoxelGrid cell = rasterize_template({{general_beam()}, true}, 16);
  EXPECT_THROW(fit_template(cell, bad), InputError);
  EXPECT_THROW(fit_template(VoxelGrid(16, 16, 8, 1.0)), InputError);
  EXPECT_THROW(fit_template(empty_cell(16)), InputError);  // no skeleton, no beams
  TemplateFitOptions restarts;
  restarts.restart_difference = -0.01;
  EXPECT_THROW(fit_template(cell, restarts), InputError);
  restarts = {};
  restarts.max_restarts = -1;
  EXPECT_THROW(fit_template(cell, restarts), InputError);
  BeamTemplate negative{{general_beam()}, true};
  negative.beams[0].r1 = -0.01;
  EXPECT_THROW(refine_template(cell, negative), InputError);
  // An empty template is no error: nothing to refine, everything differs.
  const TemplateFit none = refine_template(cell, BeamTemplate{});
  EXPECT_TRUE(none.fitted.beams.empty());
  ASSERT_EQ(none.objective.size(), 1u);
  EXPECT_NEAR(none.voxel_difference, double(solid_count(cell)) / cell.size(), 1e-15);
}

TEST(FamiliesFit, FitFromItsOwnSkeleton) {
  const int n = 32;
  BeamTemplate truth;
  truth.beams.push_back({Vec3(0, 0, 0), Vec3(0.5, 0, 0), 0.06, 0.06, 0});
  truth.beams.push_back({Vec3(0, 0, 0), Vec3(0.5, 0.5, 0.5), 0.045, 0.045, 0});
  const VoxelGrid target = rasterize_template(truth, n);
  const TemplateFit fit = fit_template(target);
  std::printf(
      "[ measured ] own skeleton: %zu beams, objective %.3g -> %.3g in %zu steps, voxel difference %.4f, "
      "solid fraction %.4f\n",
      fit.fitted.beams.size(), fit.objective.front(), fit.objective.back(), fit.objective.size() - 1,
      fit.voxel_difference, double(solid_count(target)) / target.size());
  for (const Beam& b : fit.fitted.beams)
    std::printf("[ measured ]   beam (%.3f %.3f %.3f)-(%.3f %.3f %.3f) r %.4f %.4f theta %.3f\n", b.a.x(), b.a.y(),
                b.a.z(), b.b.x(), b.b.y(), b.b.z(), b.r0, b.r1, b.theta);
  EXPECT_EQ(fit.fitted.beams.size(), 2u);
  EXPECT_LT(fit.voxel_difference, 0.05);
  for (std::size_t i = 1; i < fit.objective.size(); ++i) EXPECT_LE(fit.objective[i], fit.objective[i - 1]);
  // A free beam: its skeleton is shorter than the beam by about its
  // thickness, and the fit grows it back.
  BeamTemplate free_beam;
  free_beam.beams.push_back(general_beam());
  const VoxelGrid single = rasterize_template(free_beam, n);
  const TemplateFit lone = fit_template(single);
  std::printf("[ measured ] free beam from its skeleton: %zu beams, voxel difference %.4f, objective %.3g -> %.3g\n",
              lone.fitted.beams.size(), lone.voxel_difference, lone.objective.front(), lone.objective.back());
  EXPECT_GE(lone.fitted.beams.size(), 1u);
  EXPECT_LE(lone.fitted.beams.size(), 2u);
  EXPECT_LT(lone.voxel_difference, 0.01);
}

TEST(FamiliesFit, FitsTemplateDrawnCellsFromTheirSkeletons) {
  // One-beam templates drawn at 16^3 where a beam's images meet near, not
  // at, a point they share: body-centred lattices whose beams start off the
  // corner along an axis, and cube frames whose edges bend out at their
  // midpoints. The skeleton puts the joint on the shared point, or runs
  // straight along the edge.
  struct Case {
    const char* name;
    Beam beam;
  };
  const Case cases[] = {
      {"body-centred, corner end 1.9 voxels off", {Vec3(0.12, 0, 0), Vec3(0.5, 0.5, 0.5), 0.088, 0.088, 0}},
      {"body-centred, corner end 1.3 voxels off", {Vec3(0.08, 0, 0), Vec3(0.5, 0.5, 0.5), 0.104, 0.104, 0}},
      {"frame, edge bent 1.3 voxels", {Vec3(0, 0, 0), Vec3(0.5, 0.08, 0), 0.096, 0.096, 0}},
      {"frame, edge bent 2.6 voxels", {Vec3(0, 0, 0), Vec3(0.5, 0.16, 0), 0.12, 0.12, 0}},
  };
  const int n = 16;
  for (const Case& c : cases) {
    BeamTemplate truth;
    truth.beams.push_back(c.beam);
    const VoxelGrid target = rasterize_template(truth, n);
    const TemplateFit fit = fit_template(target);
    std::printf(
        "[ measured ] %s: %zu beams, voxel difference %.4f, objective %.3g (the drawing template's %.3g), "
        "%d steps, %d evaluations\n",
        c.name, fit.fitted.beams.size(), fit.voxel_difference, fit.objective.back(), template_objective(target, truth),
        fit.steps, fit.evaluations);
    EXPECT_LT(fit.voxel_difference, 0.02) << c.name;
    EXPECT_DOUBLE_EQ(fit.objective.back(), template_objective(target, fit.fitted)) << c.name;
    for (std::size_t i = 1; i < fit.objective.size(); ++i) EXPECT_LE(fit.objective[i], fit.objective[i - 1]) << c.name;
  }
}

}  // namespace
}  // namespace msfab
