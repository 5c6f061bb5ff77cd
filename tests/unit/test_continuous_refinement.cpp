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
