// Matrix-free multigrid-preconditioned CG on periodic voxel grids
// (solve/periodic_grid_multigrid.hpp): Galerkin coarse operators against
// explicit triple products, a symmetric cycle, agreement with the direct
// cell solver, mesh-independent iteration counts, thread independence, and
// convergence of a sphere inclusion up to 64^3.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <random>

#include "core/errors.hpp"
#include "homog/periodic_homogenization.hpp"
#include "material/linear_isotropic.hpp"
#include "solve/periodic_grid_multigrid.hpp"

namespace msfab {
namespace {

Mat24 rest_stiffness(double E, double nu, double h) {
  return voxel_stiffness(std::make_shared<LinearIsotropic>(E, nu), h);
}

// Two materials mixed per voxel with random weights (a SIMP-like field).
VoxelStiffnessField random_field(int nx, int ny, int nz, unsigned seed) {
  VoxelStiffnessField f;
  f.nx = nx, f.ny = ny, f.nz = nz, f.h = 1.0 / nx;
  f.basis = {rest_stiffness(1.0, 0.3, f.h), rest_stiffness(0.05, 0.45, f.h)};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  f.weights.resize(2 * f.voxels());
  for (std::int64_t v = 0; v < f.voxels(); ++v) f.weights[2 * v] = u(rng), f.weights[2 * v + 1] = 1.0;
  return f;
}

VoxelGrid periodic_sphere_inclusion(int n, double radius_fraction, int inside, int outside) {
  VoxelGrid g(n, n, n, 1.0 / n, outside);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        if ((g.voxel_center(i, j, k) - Vec3(0.5, 0.5, 0.5)).norm() < radius_fraction) g.at(i, j, k) = inside;
  return g;
}

std::vector<MaterialPtr> palette() {
  return {nullptr, std::make_shared<LinearIsotropic>(1e6, 0.3), std::make_shared<LinearIsotropic>(1e4, 0.45)};
}

VecX zero_mean_random(Eigen::Index n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  VecX x(n);
  for (Eigen::Index i = 0; i < n; ++i) x[i] = g(rng);
  for (int d = 0; d < 3; ++d) x(Eigen::seqN(d, n / 3, 3)).array() -= x(Eigen::seqN(d, n / 3, 3)).mean();
  return x;
}

TEST(PeriodicMultigrid, CoarseOperatorsArePTransposeKP) {
  PeriodicMultigridOptions o;
  o.coarsest_nodes = 8;  // 8^3 -> 4^3 (assembled, smoothed) -> 2^3 (factorized)
  PeriodicGridMultigrid mg(random_field(8, 8, 8, 1), o);
  ASSERT_EQ(mg.num_levels(), 3);
  EXPECT_EQ(mg.level_dims(1), (std::array<int, 3>{4, 4, 4}));
  for (int l = 0; l + 1 < mg.num_levels(); ++l) {
    const SpMat P = mg.prolongation(l);
    const SpMat expected = SpMat(P.transpose() * mg.level_operator(l) * P);
    const MatX difference = MatX(mg.level_operator(l + 1)) - MatX(expected);
    EXPECT_LT(difference.norm(), 1e-12 * MatX(expected).norm()) << "level " << l + 1;
  }
  // P reproduces translations, so every level annihilates them.
  for (int l = 0; l < mg.num_levels(); ++l) {
    const SpMat A = mg.level_operator(l);
    VecX t = VecX::Zero(A.rows());
    t(Eigen::seqN(1, A.rows() / 3, 3)).setOnes();
    EXPECT_LT((A * t).norm(), 1e-12 * A.norm()) << "level " << l;
  }
}

TEST(PeriodicMultigrid, CycleIsSymmetricAndPositiveOnZeroMeanFields) {
  PeriodicGridMultigrid mg(random_field(8, 8, 12, 2));
  const Eigen::Index n = 3 * 8 * 8 * 12;
  const VecX x = zero_mean_random(n, 3), y = zero_mean_random(n, 4);
  const double xMy = x.dot(mg.apply_preconditioner(y)), yMx = y.dot(mg.apply_preconditioner(x));
  EXPECT_NEAR(xMy, yMx, 1e-10 * std::abs(xMy));
  EXPECT_GT(x.dot(mg.apply_preconditioner(x)), 0.0);
}

TEST(PeriodicMultigrid, SolvesAgainstTheAssembledOperator) {
  PeriodicGridMultigrid mg(random_field(12, 8, 8, 5));
  const VecX b = zero_mean_random(3 * 12 * 8 * 8, 6);
  const VecX x = mg.solve(b);
  const SpMat A = mg.level_operator(0);
  EXPECT_LT((A * x - b).norm(), 1e-7 * b.norm());
  VecX y;
  mg.multiply(x, y);
  EXPECT_LT((y - A * x).norm(), 1e-13 * y.norm());
  EXPECT_LT(mg.stats().iterations, 30);
}

TEST(PeriodicMultigrid, BitwiseIdenticalForOneAndTwoThreads) {
  VecX x[2];
  for (int t = 0; t < 2; ++t) {
    PeriodicMultigridOptions o;
    o.threads = t + 1;
    PeriodicGridMultigrid mg(random_field(16, 16, 16, 7), o);
    x[t] = mg.solve(zero_mean_random(3 * 16 * 16 * 16, 8));
  }
  EXPECT_EQ((x[0] - x[1]).cwiseAbs().maxCoeff(), 0.0);
}

TEST(PeriodicMultigrid, HomogenizationMatchesTheDirectSolverWithVoid) {
  // Stiff sphere in soft matrix, and a soft sphere in void-free stiff
  // matrix with a void channel: contrast 100 and 1e6 (void).
  VoxelGrid with_void = periodic_sphere_inclusion(16, 0.3, 1, 2);
  for (int a = 0; a < 16; ++a)
    for (int b = 0; b < 3; ++b) with_void.at(a, b, 0) = 0;  // a void slab along x
  for (const VoxelGrid& cell : {periodic_sphere_inclusion(16, 0.3, 1, 2), with_void}) {
    HomogenizationOptions direct, multigrid;
    direct.solver = "cholmod";
    multigrid.solver = "matrix-free";
    multigrid.tolerance = 1e-9;
    const HomogenizationResult a = homogenize(cell, palette(), direct);
    const HomogenizationResult b = homogenize(cell, palette(), multigrid);
    EXPECT_EQ(a.solver, "cholmod");
    EXPECT_EQ(b.solver, "matrix-free");
    EXPECT_LT((a.C - b.C).norm(), 1e-8 * a.C.norm());
    std::printf("[periodic-mg] 16^3 %s: |dC|/|C| %.2e, %d CG iterations (6 cases), direct %.2f s, multigrid %.2f s\n",
                cell.ids[0] == 0 ? "with void" : "two materials", (a.C - b.C).norm() / a.C.norm(), b.iterations,
                a.seconds, b.seconds);
  }
}

TEST(PeriodicMultigrid, IterationsAreNearlyIndependentOfTheGrid) {
  HomogenizationOptions o;
  o.solver = "matrix-free";
  int iterations[2];
  for (int t = 0; t < 2; ++t) {
    const int n = t == 0 ? 16 : 32;
    iterations[t] = homogenize(periodic_sphere_inclusion(n, 0.3, 1, 2), palette(), o).iterations;
    std::printf("[periodic-mg] sphere %d^3: %d CG iterations over 6 cases\n", n, iterations[t]);
  }
  EXPECT_LE(iterations[1], iterations[0] + 12);  // 6 cases: at most 2 more per case
}

TEST(PeriodicMultigrid, SphereInclusionConvergesUpTo64Cubed) {
  // The same sphere at 16^3, 32^3, 64^3: the differences of E and G shrink.
  // A 64^3 cell (786k unknowns) is where the direct solver stops being usable.
  std::vector<CubicModuli> m;
  for (int n : {16, 32, 64}) {
    const auto t0 = std::chrono::steady_clock::now();
    const HomogenizationResult r = homogenize(periodic_sphere_inclusion(n, 0.3, 1, 2), palette());
    m.push_back(cubic_moduli(r.C));
    EXPECT_LT(cubic_deviation(r.C), 1e-6);
    std::printf("[periodic-mg] sphere n=%d (%s): E %.6g nu %.6f G %.6g, %d iterations, %.2f s\n", n, r.solver.c_str(),
                m.back().E, m.back().nu, m.back().G, r.iterations,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  // Staircase error of a voxelized sphere: about first order in h.
  EXPECT_LT(std::abs(m[2].E - m[1].E), 0.5 * std::abs(m[1].E - m[0].E));
  EXPECT_LT(std::abs(m[2].G - m[1].G), 0.5 * std::abs(m[1].G - m[0].G));
  EXPECT_LT(std::abs(m[2].E - m[1].E) / m[2].E, 0.05);
}

// Three orthogonal bars, 2 voxels thick, through a 40^3 cell of void at
// 1e-9 of the solid's stiffness: a contrast single precision cannot
// resolve, so the rounded coarse operators are indefinite and CG finds
// r . M^-1 r < 0 (the homogenize stage exited 3 on it). The solver must
// detect that, switch its smoothers to double precision and converge.
TEST(PeriodicMultigrid, ExtremeContrastFallsBackToDoublePrecisionSmoothers) {
  const int n = 40;
  VoxelGrid lattice(n, n, n, 1.0 / n, 0);
  for (int a = 0; a < n; ++a)
    for (int b = n / 2 - 1; b <= n / 2; ++b)
      for (int c = n / 2 - 1; c <= n / 2; ++c) lattice.at(a, b, c) = lattice.at(b, a, c) = lattice.at(b, c, a) = 1;
  HomogenizationOptions o;
  o.solver = "matrix-free";
  o.void_stiffness = 1e-9;
  const std::vector<MaterialPtr> solid = {nullptr, std::make_shared<LinearIsotropic>(1e6, 0.3)};
  HomogenizationResult r;
  ASSERT_NO_THROW(r = homogenize(lattice, solid, o));
  EXPECT_LT(cubic_deviation(r.C), 1e-6);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Mat6>(r.C).eigenvalues().minCoeff(), 0.0);
  const CubicModuli m = cubic_moduli(r.C);
  std::printf("[periodic-mg] 2-voxel bars in void 1e-9, 40^3: E %.6g nu %.6f G %.6g, %d iterations\n", m.E, m.nu, m.G,
              r.iterations);

  // The solver itself: it switched, and the solution meets the tolerance on
  // the exact (double, matrix-free) operator.
  VoxelStiffnessField field;
  field.nx = field.ny = field.nz = n, field.h = 1.0 / n;
  field.basis = {rest_stiffness(1e6, 0.3, field.h)};
  field.weights.resize(field.voxels());
  for (std::int64_t v = 0; v < field.voxels(); ++v) field.weights[v] = lattice.ids[v] ? 1.0 : 1e-9;
  // Tolerance 1e-6 as homogenization uses: at this contrast round-off in
  // the cycle limits the attainable residual to about 1e-7.
  PeriodicMultigridOptions mo;
  mo.tolerance = 1e-6;
  PeriodicGridMultigrid mg(field, mo);
  EXPECT_TRUE(mg.single_precision_smoothers());
  const VecX b = zero_mean_random(3 * field.voxels(), 3);
  const VecX x = mg.solve(b);
  EXPECT_FALSE(mg.single_precision_smoothers());
  VecX y;
  mg.multiply(x, y);
  EXPECT_LT((y - b).norm(), 1.01e-6 * b.norm());

  // An ordinary contrast keeps single precision.
  PeriodicGridMultigrid ordinary(random_field(16, 16, 16, 4));
  ordinary.solve(zero_mean_random(3 * 16 * 16 * 16, 5));
  EXPECT_TRUE(ordinary.single_precision_smoothers());
}

TEST(PeriodicMultigrid, BadGridsAndOptionsAreInputErrors) {
  EXPECT_THROW(PeriodicGridMultigrid(random_field(6, 6, 5, 1)), InputError);
  EXPECT_THROW(PeriodicGridMultigrid(random_field(2, 2, 2, 1)), InputError);
  VoxelStiffnessField wrong = random_field(8, 8, 8, 1);
  wrong.weights.pop_back();
  EXPECT_THROW(PeriodicGridMultigrid{wrong}, InputError);
  PeriodicMultigridOptions o;
  o.tolerance = 0;
  EXPECT_THROW(PeriodicGridMultigrid(random_field(8, 8, 8, 1), o), InputError);
  HomogenizationOptions h;
  h.solver = "matrix-free";
  EXPECT_THROW(homogenize(VoxelGrid(6, 6, 5, 1e-3, 1), palette(), h), InputError);
  h.solver = "lu";
  EXPECT_THROW(homogenize(VoxelGrid(8, 8, 8, 1e-3, 1), palette(), h), InputError);
  EXPECT_EQ(homogenization_solver(32, 32, 32, "auto"), "matrix-free");
  EXPECT_EQ(homogenization_solver(16, 16, 16, "auto"), "matrix-free");
  EXPECT_EQ(homogenization_solver(10, 10, 10, "auto"), "cholmod");
  EXPECT_EQ(homogenization_solver(64, 64, 1, "auto"), "cholmod");
  EXPECT_EQ(homogenization_solver(30, 30, 30, "auto"), "matrix-free");
  EXPECT_EQ(homogenization_solver(33, 32, 32, "auto"), "cholmod");
}

}  // namespace
}  // namespace msfab
