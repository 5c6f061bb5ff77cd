// The continuous step (thesis §3.2.2): the objective's gradient against
// finite differences, symmetry of the design, and MMA moving a structure
// towards a target outside its reach.
#include <gtest/gtest.h>

#include "core/errors.hpp"
#include "gamut/continuous_refinement.hpp"
#include "gamut/material_space.hpp"
#include "gamut/structure_ops.hpp"
#include "homog/periodic_homogenization.hpp"
#include "material/linear_isotropic.hpp"

namespace msfab {
namespace {

const MaterialPtr kStiff = std::make_shared<LinearIsotropic>(1e6, 0.3);
const MaterialPtr kSoft = std::make_shared<LinearIsotropic>(1e4, 0.45);

// A square frame: stiff bars along the cell edges' mid-lines.
VoxelGrid frame_2d(int n) {
  VoxelGrid c(n, n, 1, 1.0 / n, 2);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      if (std::abs(2 * i + 1 - n) <= 3 || std::abs(2 * j + 1 - n) <= 3) c.at(i, j, 0) = 1;
  return c;
}

std::vector<double> wobbly(int n, double lo, double hi) {
  std::vector<double> x(n);
  for (int i = 0; i < n; ++i) x[i] = lo + (hi - lo) * (0.5 + 0.5 * std::sin(1.7 * i + 0.3));
  return x;
}

void expect_gradient_matches(const ContinuousCellProblem& problem, const std::vector<double>& x, double tol) {
  std::vector<double> g;
  problem.objective(x, &g);
  ASSERT_EQ(static_cast<int>(g.size()), problem.variables());
  const double step = 1e-6;
  double gmax = 0;
  for (double v : g) gmax = std::max(gmax, std::abs(v));
  for (int i = 0; i < problem.variables(); i += std::max(1, problem.variables() / 12)) {
    std::vector<double> a = x, b = x;
    a[i] += step, b[i] -= step;
    const double fd = (problem.objective(a, nullptr) - problem.objective(b, nullptr)) / (2 * step);
    EXPECT_NEAR(g[i], fd, tol * gmax) << "variable " << i;
  }
}

TEST(ContinuousRefinement, GradientMatchesFiniteDifferences2D) {
  RefinementTarget target;
  target.G = Mat3::Identity() * 1e-5;
  target.G(0, 1) = target.G(1, 0) = 3e-6;
  target.rho = 0.4;
  ContinuousOptions o;
  o.filter_radius = 1.8;
  const ContinuousCellProblem problem(8, 8, 1, 1.0 / 8, kStiff, kSoft, target, o);
  EXPECT_EQ(problem.variables(), 10);  // 4 x 4 quarter folded by the diagonal
  expect_gradient_matches(problem, wobbly(problem.variables(), 0.1, 0.9), 1e-5);
}

TEST(ContinuousRefinement, GradientMatchesFiniteDifferences3DWithVoidAndOrthotropicSymmetry) {
  RefinementTarget target;
  target.G = Mat6::Identity() * 1e-4;
  target.rho = 0.6;
  ContinuousOptions o;
  o.symmetry = CellSymmetry::orthotropic;
  const ContinuousCellProblem problem(4, 4, 6, 1.0 / 4, kStiff, nullptr, target, o);
  EXPECT_EQ(problem.variables(), 2 * 2 * 3);
  expect_gradient_matches(problem, wobbly(problem.variables(), 0.3, 0.95), 1e-5);
}

TEST(ContinuousRefinement, FilteredDensitiesKeepTheSymmetryAndAverage) {
  RefinementTarget target;
  target.G = Mat3::Identity();
  const ContinuousCellProblem problem(10, 10, 1, 0.1, kStiff, kSoft, target, ContinuousOptions{});
  const std::vector<double> x = wobbly(problem.variables(), 0, 1);
  const VoxelGrid t = problem.threshold(x, 1, 2);
  EXPECT_TRUE(has_cubic_symmetry(t));
  // Rows are normalized: a constant design stays constant.
  for (double v : problem.filtered(std::vector<double>(problem.variables(), 0.7))) EXPECT_NEAR(v, 0.7, 1e-12);
}

// The filter as one stencil against the definition: x~_v = sum_w
// max(0, R - |v - w|) x_w / sum_w max(0, R - |v - w|), |v - w| the periodic
// distance, on a box so small along y that the cone wraps onto itself.
TEST(ContinuousRefinement, FilterStencilEqualsThePeriodicConeOnASmallBox) {
  const int nx = 6, ny = 4, nz = 5;
  const double R = 2.6;
  RefinementTarget target;
  target.G = Mat6::Identity() * 1e-4;
  ContinuousOptions o;
  o.symmetry = CellSymmetry::orthotropic;
  o.filter_radius = R;
  const ContinuousCellProblem problem(nx, ny, nz, 1.0 / nx, kStiff, nullptr, target, o);
  VoxelGrid s(nx, ny, nz, 1.0 / nx);
  const auto mirror = [](int i, int n) { return std::min(i, n - 1 - i); };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) s.at(i, j, k) = (mirror(i, nx) + 2 * mirror(j, ny) + 3 * mirror(k, nz)) % 3 == 0;
  const std::vector<double> xt = problem.filtered(problem.start(s, 1));
  const double high = 0.5 + o.start_offset, low = 0.5 - o.start_offset;
  const auto gap = [](int a, int b, int n) { return std::min(std::abs(a - b), n - std::abs(a - b)); };
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        double sum = 0, weighted = 0;
        for (int c = 0; c < nz; ++c)
          for (int b = 0; b < ny; ++b)
            for (int a = 0; a < nx; ++a) {
              const double d = std::sqrt(double(gap(i, a, nx) * gap(i, a, nx) + gap(j, b, ny) * gap(j, b, ny) +
                                                gap(k, c, nz) * gap(k, c, nz)));
              const double w = std::max(0.0, R - d);
              sum += w;
              weighted += w * (s.at(a, b, c) == 1 ? high : low);
            }
        EXPECT_NEAR(xt[s.index(i, j, k)], weighted / sum, 1e-14) << i << " " << j << " " << k;
      }
}

TEST(ContinuousRefinement, MmaMovesTheStructureTowardsAStifferShear) {
  // Start: a cross frame (weak in shear); target: its own properties with
  // the shear modulus doubled. The refined, thresholded structure must
  // close at least a third of the gap in G and stay symmetric.
  const VoxelGrid start = frame_2d(16);
  const std::vector<MaterialPtr> pal = {nullptr, kStiff, kSoft};
  const MaterialSpace space(MaterialSpaceKind::cubic2d, 1e6);
  const PlaneStrainResult h0 = homogenize_plane_strain(start, pal);
  const VecX p0 = space.properties_2d(h0.C, h0.full.volume_fraction[1]);
  VecX q = p0;
  q[2] *= 2;
  RefinementTarget target;
  target.G = space.tensor_2d(q).inverse();
  target.rho = q[3];
  ContinuousOptions o;
  o.max_iterations = 40;
  const ContinuousResult r = refine_structure(start, 1, 2, kStiff, kSoft, target, o);
  EXPECT_GT(r.evaluations, 10);
  EXPECT_LT(r.best_objective, 0.5 * r.start_objective);
  const PlaneStrainResult h1 = homogenize_plane_strain(r.structure, pal);
  const VecX p1 = space.properties_2d(h1.C, h1.full.volume_fraction[1]);
  EXPECT_GT(p1[2] - p0[2], (q[2] - p0[2]) / 3) << "G " << p0[2] << " -> " << p1[2] << ", target " << q[2];
  EXPECT_TRUE(has_cubic_symmetry(r.structure));
}

// The directed objective and its floors: gradients against central
// differences in the three spaces (2D square, 2D orthotropic, 3D cubic).
struct DirectedCase {
  MaterialSpaceKind kind;
  int nx, ny, nz;
  CellSymmetry symmetry;
};

TEST(ContinuousRefinement, DirectedObjectiveAndFloorGradientsMatchFiniteDifferences) {
  for (const DirectedCase& c : {DirectedCase{MaterialSpaceKind::cubic2d, 8, 8, 1, CellSymmetry::cubic},
                                DirectedCase{MaterialSpaceKind::orthotropic2d, 8, 6, 1, CellSymmetry::orthotropic},
                                DirectedCase{MaterialSpaceKind::cubic3d, 4, 4, 4, CellSymmetry::cubic}}) {
    const MaterialSpace space(c.kind, 1e6);
    DirectedTarget target;
    target.direction = VecX::LinSpaced(space.dimension(), -1.0, 0.7);  // every property counts
    target.floor = VecX::Constant(space.dimension(), 0.2);
    ContinuousOptions o;
    o.symmetry = c.symmetry;
    const ContinuousCellProblem problem(c.nx, c.ny, c.nz, 1.0 / c.nx, kStiff, c.nz == 1 ? kSoft : nullptr, space,
                                        target, o);
    ASSERT_EQ(problem.constraints(), space.dimension());
    const std::vector<double> x = wobbly(problem.variables(), 0.2, 0.9);
    expect_gradient_matches(problem, x, 1e-5);
    for (int k = 0; k < problem.constraints(); ++k) {
      std::vector<double> g;
      problem.constraint(k, x, &g);
      double gmax = 0;
      for (double v : g) gmax = std::max(gmax, std::abs(v));
      for (int i = 0; i < problem.variables(); i += std::max(1, problem.variables() / 8)) {
        std::vector<double> a = x, b = x;
        a[i] += 1e-6, b[i] -= 1e-6;
        const double fd = (problem.constraint(k, a, nullptr) - problem.constraint(k, b, nullptr)) / 2e-6;
        EXPECT_NEAR(g[i], fd, 1e-5 * gmax) << "space " << int(c.kind) << " floor " << k << " variable " << i;
      }
    }
    // The objective is -d . u of the grey design's own properties.
    EXPECT_NEAR(problem.objective(x, nullptr), -target.direction.dot(problem.unit_properties(x)), 1e-12);
  }
}

TEST(ContinuousRefinement, PropertyGradientsMatchFiniteDifferences) {
  for (MaterialSpaceKind kind :
       {MaterialSpaceKind::cubic2d, MaterialSpaceKind::orthotropic2d, MaterialSpaceKind::cubic3d}) {
    const MaterialSpace space(kind, 1e6);
    const int m = kind == MaterialSpaceKind::cubic3d ? 6 : 3;
    MatX C = MatX::Identity(m, m) * 3e5;
    for (int i = 0; i < std::min(m, 3); ++i)
      for (int j = 0; j < std::min(m, 3); ++j) C(i, j) += i == j ? 2e5 * (1 + 0.1 * i) : 1e5;
    if (m == 3) C(2, 2) = 1.5e5;
    std::vector<MatX> d;
    const VecX p = space.properties_with_gradient(C, 0.4, &d);
    for (int k = 0; k + 1 < p.size(); ++k)
      for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j) {
          MatX a = C, b = C;
          const double step = 1e-5 * C.cwiseAbs().maxCoeff();
          a(i, j) += step, b(i, j) -= step;
          const double fd = (space.properties_with_gradient(a, 0.4, nullptr)[k] -
                             space.properties_with_gradient(b, 0.4, nullptr)[k]) /
                            (2 * step);
          EXPECT_NEAR(d[k](i, j), fd, 1e-6 * d[k].cwiseAbs().maxCoeff())
              << "kind " << int(kind) << " property " << k << " entry " << i << "," << j;
        }
    // The same properties as the space's own readers.
    if (kind == MaterialSpaceKind::cubic3d) {
      EXPECT_LT((p - space.properties(Mat6(C), 0.4)).norm(), 1e-12 * p.norm());
    } else {
      EXPECT_LT((p - space.properties_2d(Mat3(C), 0.4)).norm(), 1e-12 * p.norm());
    }
  }
}

// A square lattice of stiff bars in void, its bars `width` voxels wide
// (nu near 0: the bars do not couple the axes).
VoxelGrid lattice_2d(int n, int width) {
  VoxelGrid c(n, n, 1, 1.0 / n, 0);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      if (std::abs(2 * i + 1 - n) < 2 * width || std::abs(2 * j + 1 - n) < 2 * width) c.at(i, j, 0) = 1;
  return c;
}

TEST(ContinuousRefinement, DirectedPushesMovePoissonsRatioTheRequestedWay) {
  // From the same lattice, min_nu and max_nu move the printable structure's
  // nu down and up; E stays above its floor; the results stay symmetric
  // and connected (cleaning them again changes nothing).
  const int n = 16;
  const VoxelGrid start = lattice_2d(n, 3);
  const std::vector<MaterialPtr> pal = {nullptr, kStiff};
  const MaterialSpace space(MaterialSpaceKind::cubic2d, 1e6 / (1 - 0.09));
  const PlaneStrainResult h0 = homogenize_plane_strain(start, pal);
  const VecX u0 = space.normalize(space.properties_2d(h0.C, h0.full.volume_fraction[1]));
  ContinuousOptions o;
  o.max_iterations = 100;
  o.projection_beta = 16;
  o.filter_radius = 2.5;
  for (double sign : {-1.0, 1.0}) {
    DirectedTarget t;
    t.direction = VecX::Zero(4);
    t.direction[1] = sign;
    t.floor = VecX::Constant(4, -1.0);
    t.floor[0] = u0[0] - 0.25;
    const ContinuousResult r = refine_structure_directed(start, 1, 0, kStiff, nullptr, space, t, o);
    ASSERT_GT(r.structure.count_solid(), 0);
    const PlaneStrainResult h1 = homogenize_plane_strain(r.structure, pal);
    const VecX p1 = space.properties_2d(h1.C, h1.full.volume_fraction[1]);
    const VecX u1 = space.normalize(p1);
    const double nu0 = space.denormalize(u0)[1];
    std::printf("direction %+g: nu %.3f -> %.3f, E %.3g -> %.3g (threshold %.2f, %d evaluations)\n", sign, nu0, p1[1],
                space.denormalize(u0)[0], p1[0], r.threshold, r.evaluations);
    EXPECT_GT(sign * (p1[1] - nu0), 0.1) << "nu did not move by 0.1 the requested way";
    EXPECT_GE(u1[0], t.floor[0] - 1e-3) << "E fell below its floor";
    EXPECT_TRUE(has_cubic_symmetry(r.structure));
    VoxelGrid again = r.structure;
    const CleanupReport cleaned = clean_structure(again);
    EXPECT_EQ(cleaned.removed_voxels, 0);
  }
}

TEST(ContinuousRefinement, BadInputIsRejected) {
  RefinementTarget target;
  target.G = Mat6::Identity();
  EXPECT_THROW((void)ContinuousCellProblem(8, 8, 1, 0.1, kStiff, kSoft, target, ContinuousOptions{}), InputError);
  target.G = Mat3::Identity();
  ContinuousOptions o;
  o.start_offset = 0.6;
  EXPECT_THROW((void)ContinuousCellProblem(8, 8, 1, 0.1, kStiff, kSoft, target, o), InputError);
}

}  // namespace
}  // namespace msfab
