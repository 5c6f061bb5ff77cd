// The gamut level set (thesis §3.2.3): signed distance of known shapes from
// sample points, gradients against finite differences, bad input.
#include <gtest/gtest.h>

#include <random>

#include "core/errors.hpp"
#include "gamut/level_set.hpp"

namespace msfab {
namespace {

double u01(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

// Points filling a shape (rejection sampling in the unit cube).
template <class Inside>
std::vector<VecX> fill(int dim, int count, std::uint64_t seed, Inside inside) {
  std::mt19937_64 rng(seed);
  std::vector<VecX> pts;
  while (static_cast<int>(pts.size()) < count) {
    VecX p(dim);
    for (int a = 0; a < dim; ++a) p[a] = u01(rng);
    if (inside(p)) pts.push_back(p);
  }
  return pts;
}

TEST(GamutLevelSet, BallIsItsSignedDistance) {
  const VecX c = VecX::Constant(3, 0.5);
  const double R = 0.3;
  const auto pts = fill(3, 30000, 1, [&](const VecX& p) { return (p - c).norm() < R; });
  LevelSetOptions o;
  o.cells = 32;
  const GamutLevelSet ls = GamutLevelSet::from_points(pts, o);
  // Tolerance: a grid cell (first-order fast marching, interpolation) plus
  // the implicit function's radius (its zero set sits within r of the
  // samples' hull).
  const double tol = 1.5 * ls.spacing();
  std::mt19937_64 rng(2);
  double worst = 0;
  for (int i = 0; i < 400; ++i) {
    VecX p(3);
    for (int a = 0; a < 3; ++a) p[a] = u01(rng);
    const double exact = (p - c).norm() - R;
    worst = std::max(worst, std::abs(ls.value(p) - exact));
  }
  std::printf("[level set] 3D ball: max |Phi - exact| %.4f (h %.4f)\n", worst, ls.spacing());
  EXPECT_LT(worst, tol);
  EXPECT_LT(ls.value(c), -0.2);
  EXPECT_GT(ls.value(VecX::Zero(3)), 0.4);
}

TEST(GamutLevelSet, BoxIn2DAndBallIn4D) {
  // 2D box [0.2, 0.7] x [0.3, 0.8].
  const auto box =
      fill(2, 20000, 3, [](const VecX& p) { return p[0] > 0.2 && p[0] < 0.7 && p[1] > 0.3 && p[1] < 0.8; });
  LevelSetOptions o;
  o.cells = 48;
  const GamutLevelSet ls = GamutLevelSet::from_points(box, o);
  auto box_sdf = [](const VecX& p) {
    const double dx = std::max(0.2 - p[0], p[0] - 0.7), dy = std::max(0.3 - p[1], p[1] - 0.8);
    if (dx <= 0 && dy <= 0) return std::max(dx, dy);
    return std::hypot(std::max(dx, 0.0), std::max(dy, 0.0));
  };
  std::mt19937_64 rng(4);
  double worst = 0;
  for (int i = 0; i < 400; ++i) {
    VecX p(2);
    p << u01(rng), u01(rng);
    worst = std::max(worst, std::abs(ls.value(p) - box_sdf(p)));
  }
  std::printf("[level set] 2D box: max |Phi - exact| %.4f (h %.4f)\n", worst, ls.spacing());
  EXPECT_LT(worst, 1.5 * ls.spacing());
  // The error shrinks with the grid (r = 1.5 cells shrinks with it).
  double previous = worst;
  for (int cells : {96, 192}) {
    o.cells = cells;
    const GamutLevelSet fine = GamutLevelSet::from_points(box, o);
    double e = 0;
    std::mt19937_64 again(4);
    for (int i = 0; i < 400; ++i) {
      VecX p(2);
      p << u01(again), u01(again);
      e = std::max(e, std::abs(fine.value(p) - box_sdf(p)));
    }
    std::printf("[level set] 2D box, %d cells: max error %.4f\n", cells, e);
    EXPECT_LT(e, 0.8 * previous);
    previous = e;
  }
  // 4D ball, coarse grid.
  const VecX c = VecX::Constant(4, 0.5);
  const auto ball = fill(4, 40000, 5, [&](const VecX& p) { return (p - c).norm() < 0.35; });
  LevelSetOptions o4;
  o4.cells = 14;
  const GamutLevelSet ls4 = GamutLevelSet::from_points(ball, o4);
  worst = 0;
  for (int i = 0; i < 200; ++i) {
    VecX p(4);
    for (int a = 0; a < 4; ++a) p[a] = u01(rng);
    worst = std::max(worst, std::abs(ls4.value(p) - ((p - c).norm() - 0.35)));
  }
  std::printf("[level set] 4D ball: max |Phi - exact| %.4f (h %.4f)\n", worst, ls4.spacing());
  EXPECT_LT(worst, 1.5 * ls4.spacing());
}

TEST(GamutLevelSet, GradientMatchesFiniteDifferencesAndHasUnitLength) {
  const VecX c = VecX::Constant(3, 0.5);
  const auto pts = fill(3, 20000, 6, [&](const VecX& p) { return (p - c).norm() < 0.3; });
  const GamutLevelSet ls = GamutLevelSet::from_points(pts);
  std::mt19937_64 rng(7);
  double mean_norm = 0;
  int shell = 0;
  for (int i = 0; i < 200; ++i) {
    VecX p(3);
    for (int a = 0; a < 3; ++a) p[a] = u01(rng);
    const VecX g = ls.gradient(p);
    for (int a = 0; a < 3; ++a) {
      const double e = 1e-7;
      VecX pp = p, pm = p;
      pp[a] += e, pm[a] -= e;
      const double fd = (ls.value(pp) - ls.value(pm)) / (2 * e);
      EXPECT_NEAR(g[a], fd, 1e-5 * std::max(1.0, std::abs(fd))) << "point " << i << " axis " << a;
    }
    const double dist = (p - c).norm();
    if (dist > 0.38 && dist < 0.5) mean_norm += g.norm(), ++shell;  // away from surface and grid edge
  }
  ASSERT_GT(shell, 10);
  mean_norm /= shell;
  std::printf("[level set] mean |grad Phi| in a shell outside the ball: %.3f\n", mean_norm);
  EXPECT_NEAR(mean_norm, 1.0, 0.1);
  // Outside the grid the value keeps growing with the distance.
  VecX far = VecX::Constant(3, 1.5);
  EXPECT_GT(ls.value(far), ls.value(VecX::Constant(3, 1.0)));
  EXPECT_NEAR(ls.gradient(far).norm(), 1.0, 0.2);
}

// The zero level sits the implicit function's radius outside the samples;
// shifted(padding()) moves it back onto them (the optimizer's honest
// feasible set, docs/topopt.md "gamut_padding").
TEST(GamutLevelSet, SubtractingThePaddingPutsTheZeroLevelOnTheSamples) {
  const auto pts = fill(2, 20000, 5, [](const VecX& p) { return p.minCoeff() > 0.3 && p.maxCoeff() < 0.7; });
  LevelSetOptions o;
  o.cells = 64;
  const GamutLevelSet ls = GamutLevelSet::from_points(pts, o);
  const double h = ls.spacing(), r = ls.padding();
  EXPECT_DOUBLE_EQ(r, 1.5 * h);
  const GamutLevelSet honest = ls.shifted(r);
  EXPECT_EQ(honest.padding(), 0.0);
  // Where the samples end (x = 0.7 on the mid line) the padded set is still
  // about r inside; the shifted one is on its boundary, within a grid cell.
  const VecX edge = Eigen::Vector2d(0.7, 0.5);
  EXPECT_NEAR(ls.value(edge), -r, h);
  EXPECT_NEAR(honest.value(edge), 0.0, h);
  EXPECT_LT(honest.value(Eigen::Vector2d(0.5, 0.5)), -0.1);
  // A point r outside the samples is feasible only with the padding.
  const VecX beyond = Eigen::Vector2d(0.7 + r, 0.5);
  EXPECT_LT(ls.value(beyond), 0.5 * h);
  EXPECT_GT(honest.value(beyond), 0.5 * h);
  EXPECT_LT((honest.gradient(edge) - ls.gradient(edge)).norm(), 1e-9);
}

TEST(GamutLevelSet, BadInputIsAnInputError) {
  EXPECT_THROW(GamutLevelSet::from_points({}), InputError);
  EXPECT_THROW(GamutLevelSet::from_points({VecX::Constant(2, 0.5), VecX::Constant(3, 0.5)}), InputError);
  EXPECT_THROW(GamutLevelSet::from_points({VecX::Constant(2, 1.5)}), InputError);
  LevelSetOptions o;
  o.cells = 1;
  EXPECT_THROW(GamutLevelSet::from_points({VecX::Constant(2, 0.5)}, o), InputError);
  o.cells = 200;
  EXPECT_THROW(GamutLevelSet::from_points({VecX::Constant(5, 0.5)}, o), InputError);
}

}  // namespace
}  // namespace msfab
