// Matrix-free multigrid-preconditioned CG on a box of hexahedra with
// Dirichlet unknowns (solve/dirichlet_grid_multigrid.hpp) and its use as
// the "matrix-free" solver of GridElasticity: the product against the
// assembled matrix, level 1 against the explicit triple product P^T A P,
// agreement with a direct solve on a clamped cantilever with high-contrast
// SIMP stiffness, bounded iteration counts under refinement, thread
// independence, the basis compression of per-cell stiffness, and errors.
#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <cstdio>
#include <cstring>
#include <random>

#include "core/errors.hpp"
#include "homog/periodic_homogenization.hpp"
#include "material/linear_isotropic.hpp"
#include "solve/dirichlet_grid_multigrid.hpp"
#include "topopt/cell_grid.hpp"
#include "topopt/grid_elasticity.hpp"

namespace msfab {
namespace {

Mat24 dirichlet_rest_stiffness(double E, double nu, double h) {
  return voxel_stiffness(std::make_shared<LinearIsotropic>(E, nu), h);
}

// Two materials mixed per element with random weights; `void_fraction` of
// the elements get weight 1e-9 on the stiff one and none on the soft one
// (SIMP-like contrast).
VoxelStiffnessField dirichlet_random_field(int nx, int ny, int nz, unsigned seed, double void_fraction = 0.0) {
  VoxelStiffnessField f;
  f.nx = nx, f.ny = ny, f.nz = nz, f.h = 1.0 / nx;
  f.basis = {dirichlet_rest_stiffness(1.0, 0.3, f.h), dirichlet_rest_stiffness(0.05, 0.45, f.h)};
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  f.weights.resize(2 * f.voxels());
  for (std::int64_t v = 0; v < f.voxels(); ++v) {
    const bool empty = u(rng) < void_fraction;
    f.weights[2 * v] = empty ? 1e-9 : u(rng);
    f.weights[2 * v + 1] = empty ? 0.0 : 1.0;
  }
  return f;
}

std::int64_t node_of(int nx, int ny, int i, int j, int k) {
  return i + std::int64_t(nx + 1) * (j + std::int64_t(ny + 1) * k);
}

// Clamp the nodes with x index < layers entirely, plus the y component of
// every other node of the far bottom edge (partly fixed nodes).
std::vector<char> cantilever_mask(int nx, int ny, int nz, bool partial = true, int layers = 1) {
  std::vector<char> fixed(3 * std::size_t(nx + 1) * (ny + 1) * (nz + 1), 0);
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i < layers; ++i)
        for (int d = 0; d < 3; ++d) fixed[3 * node_of(nx, ny, i, j, k) + d] = 1;
  if (partial)
    for (int j = 0; j <= ny; j += 2) fixed[3 * node_of(nx, ny, nx, j, 0) + 1] = 1;
  return fixed;
}

VecX dirichlet_random_vector(Eigen::Index n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  VecX x(n);
  for (Eigen::Index i = 0; i < n; ++i) x[i] = g(rng);
  return x;
}

TEST(DirichletMultigrid, ProductMatchesAssembledMatrix) {
  const int nx = 6, ny = 4, nz = 4;
  DirichletGridMultigrid mg(nx, ny, nz, cantilever_mask(nx, ny, nz));
  mg.set_field(dirichlet_random_field(nx, ny, nz, 3, 0.2));
  const SpMat A = mg.fine_operator();
  EXPECT_LT((SpMat(A.transpose()) - A).norm(), 1e-12 * A.norm());
  const VecX x = dirichlet_random_vector(A.rows(), 5);
  VecX y;
  mg.multiply(x, y);
  EXPECT_LT((y - A * x).norm(), 1e-12 * (A * x).norm());
}

// The product runs by bands of element rows (multiply_rows): a grid of
// several bands, the last one partial, with void, against the assembled
// matrix, and the same bits on one and on three threads.
TEST(DirichletMultigrid, ProductAcrossBandsMatchesAssembledMatrixOnAnyThreadCount) {
  const int nx = 20, ny = 22, nz = 14;  // above the rows where the product goes parallel
  const VoxelStiffnessField field = dirichlet_random_field(nx, ny, nz, 7, 0.3);
  VecX y[2];
  for (int run = 0; run < 2; ++run) {
    DirichletMultigridOptions options;
    options.threads = run == 0 ? 1 : 3;
    DirichletGridMultigrid mg(nx, ny, nz, cantilever_mask(nx, ny, nz), options);
    mg.set_field(field);
    ASSERT_GT(3 * mg.rows(), 3 * 4096);
    const SpMat A = mg.fine_operator();
    const VecX x = dirichlet_random_vector(A.rows(), 11);
    mg.multiply(x, y[run]);
    EXPECT_LT((y[run] - A * x).norm(), 1e-12 * (A * x).norm());
  }
  EXPECT_EQ(0, std::memcmp(y[0].data(), y[1].data(), sizeof(double) * std::size_t(y[0].size())));
}

TEST(DirichletMultigrid, LevelOneIsTheGalerkinProduct) {
  const int nx = 6, ny = 4, nz = 4;
  const std::vector<char> fixed = cantilever_mask(nx, ny, nz, true, 2);
  DirichletGridMultigrid mg(nx, ny, nz, fixed);
  mg.set_field(dirichlet_random_field(nx, ny, nz, 7, 0.2));
  const SpMat A = mg.fine_operator(), P = mg.prolongation(), Ac = mg.coarse_operator();
  const SpMat reference = SpMat(P.transpose()) * A * P;
  ASSERT_EQ(Ac.rows(), reference.rows());
  // Identical except for the coarse unknowns P does not reach (at x = 0,
  // where two layers of fine nodes are clamped): there the reference row is
  // empty and the level holds a diagonal.
  const VecX reach = SpMat(P.transpose()) * VecX::Ones(P.rows());
  MatX difference = MatX(Ac) - MatX(reference);
  int unreached = 0;
  for (Eigen::Index u = 0; u < Ac.rows(); ++u)
    if (reach[u] == 0) {
      ++unreached;
      EXPECT_GT(Ac.coeff(u, u), 0.0);
      EXPECT_EQ(MatX(reference).row(u).norm(), 0.0);
      difference(u, u) = 0.0;
    }
  EXPECT_GT(unreached, 0);
  EXPECT_LT(difference.norm(), 1e-12 * MatX(reference).norm());
}

TEST(DirichletMultigrid, SolvesHighContrastCantileverLikeADirectSolver) {
  const int nx = 16, ny = 8, nz = 8;
  const std::vector<char> fixed = cantilever_mask(nx, ny, nz);
  DirichletMultigridOptions options;
  options.tolerance = 1e-10;
  options.coarse_unknowns = 200;
  DirichletGridMultigrid mg(nx, ny, nz, fixed, options);
  mg.set_field(dirichlet_random_field(nx, ny, nz, 11, 0.3));
  EXPECT_GE(mg.num_levels(), 3);
  VecX b = dirichlet_random_vector(3 * std::int64_t(nx + 1) * (ny + 1) * (nz + 1), 13);
  const VecX x = mg.solve(b);
  const SpMat A = mg.fine_operator();
  Eigen::SimplicialLDLT<SpMat> direct(A);
  ASSERT_EQ(direct.info(), Eigen::Success);
  const VecX reference = direct.solve(b);
  EXPECT_LT((x - reference).norm(), 1e-7 * reference.norm());
  EXPECT_LT((A * x - b).norm(), 1e-10 * b.norm() * 1.0001);
  // Fixed unknowns: A x = b there means x_d = b_d / s.
  for (std::size_t d = 0; d < fixed.size(); ++d) {
    const double expected = b[Eigen::Index(d)] / mg.fixed_scale();
    if (fixed[d]) {
      EXPECT_NEAR(x[Eigen::Index(d)], expected, 1e-9 * std::abs(expected));
    }
  }
}

TEST(DirichletMultigrid, IterationsStayBoundedUnderRefinement) {
  std::vector<int> iterations;
  for (int n : {8, 16, 32}) {
    const int nx = 2 * n, ny = n, nz = n;
    DirichletGridMultigrid mg(nx, ny, nz, cantilever_mask(nx, ny, nz, false));
    VoxelStiffnessField f;
    f.nx = nx, f.ny = ny, f.nz = nz, f.h = 1.0 / n;
    f.basis = {dirichlet_rest_stiffness(1.0, 0.3, f.h)};
    f.weights.assign(f.voxels(), 1.0);
    mg.set_field(f);
    // The tip load: -z on the nodes of the edge x = L, z = 0.
    VecX b = VecX::Zero(3 * std::int64_t(nx + 1) * (ny + 1) * (nz + 1));
    for (int j = 0; j <= ny; ++j) b[3 * node_of(nx, ny, nx, j, 0) + 2] = -1.0 / (ny + 1);
    mg.solve(b);
    iterations.push_back(mg.stats().iterations);
  }
  std::printf("matrix-free multigrid CG iterations at 16x8x8, 32x16x16, 64x32x32: %d %d %d\n", iterations[0],
              iterations[1], iterations[2]);
  for (int it : iterations) EXPECT_LE(it, 40);
  EXPECT_LE(iterations[2], iterations[0] + 10);
}

TEST(DirichletMultigrid, ResultDoesNotDependOnThreadCount) {
  const int nx = 16, ny = 8, nz = 8;
  VecX x[2];
  for (int t = 0; t < 2; ++t) {
    DirichletMultigridOptions options;
    options.threads = t + 1;
    options.coarse_unknowns = 200;
    DirichletGridMultigrid mg(nx, ny, nz, cantilever_mask(nx, ny, nz), options);
    mg.set_field(dirichlet_random_field(nx, ny, nz, 17, 0.3));
    x[t] = mg.solve(dirichlet_random_vector(3 * std::int64_t(nx + 1) * (ny + 1) * (nz + 1), 19));
  }
  EXPECT_EQ((x[0] - x[1]).cwiseAbs().maxCoeff(), 0.0);
}

TEST(DirichletMultigrid, RejectsBadGridsAndFields) {
  EXPECT_THROW(DirichletGridMultigrid(5, 4, 4, std::vector<char>(3 * 6 * 5 * 5, 0)), InputError);
  DirichletGridMultigrid mg(4, 4, 4, std::vector<char>(3 * 125, 0));
  EXPECT_THROW(mg.set_field(dirichlet_random_field(4, 4, 2, 1)), InputError);
  // Nothing held: the coarse operator is singular (rigid motions).
  EXPECT_THROW(mg.set_field(dirichlet_random_field(4, 4, 4, 1)), NumericalError);
  DirichletGridMultigrid all(2, 2, 2, std::vector<char>(3 * 27, 1));
  EXPECT_THROW(all.set_field(dirichlet_random_field(2, 2, 2, 1)), InputError);
}

// Per-cell stiffness of a topology-optimization grid: SIMP (C proportional
// to one tensor) compresses to one base matrix, a cubic field to three, and
// the element matrices are reproduced.
TEST(DirichletMultigrid, StiffnessFieldCompressesProportionalPairs) {
  const CellGrid grid(3, 4, 2, 2, 0.5);
  const int m = grid.voigt(), Q = grid.voigt_pairs();
  auto pairs_of = [&](const MatX& C) {
    VecX row(Q);
    for (int s = 0; s < m; ++s)
      for (int t = s; t < m; ++t) row[CellGrid::pair_index(s, t, m)] = C(s, t);
    return row;
  };
  auto cubic = [](double c11, double c12, double c44) {
    MatX C = MatX::Zero(6, 6);
    for (int s = 0; s < 3; ++s) {
      for (int t = 0; t < 3; ++t) C(s, t) = s == t ? c11 : c12;
      C(3 + s, 3 + s) = c44;
    }
    return C;
  };
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(0.1, 1.0);
  MatX simp(grid.cells(), Q), cubic_pairs(grid.cells(), Q);
  const MatX C0 = cubic(1.35, 0.58, 0.38);
  for (std::int64_t c = 0; c < grid.cells(); ++c) {
    simp.row(c) = pairs_of(std::pow(u(rng), 3) * C0).transpose();
    cubic_pairs.row(c) = pairs_of(cubic(2 + u(rng), u(rng), u(rng))).transpose();
  }
  const VoxelStiffnessField one = stiffness_field(grid, simp), three = stiffness_field(grid, cubic_pairs);
  EXPECT_EQ(one.basis_size(), 1);
  EXPECT_EQ(three.basis_size(), 3);
  for (std::int64_t c = 0; c < grid.cells(); ++c) {
    const MatX reference = grid.element_stiffness(cubic(cubic_pairs(c, 0), cubic_pairs(c, 1), cubic_pairs(c, 15)));
    EXPECT_LT((MatX(three.element(c)) - reference).norm(), 1e-12 * reference.norm());
    MatX C(6, 6);
    for (int s = 0; s < m; ++s)
      for (int t = s; t < m; ++t) C(s, t) = C(t, s) = simp(c, CellGrid::pair_index(s, t, m));
    const MatX simp_reference = grid.element_stiffness(C);
    EXPECT_LT((MatX(one.element(c)) - simp_reference).norm(), 1e-12 * simp_reference.norm());
  }
}

// GridElasticity: "matrix-free" and CHOLMOD give the same displacement,
// prescribed values included.
TEST(DirichletMultigrid, GridElasticityMatrixFreeMatchesCholmod) {
  const CellGrid grid(3, 12, 6, 4, 1.0);
  std::vector<char> fixed(grid.unknowns(), 0);
  VecX prescribed = VecX::Zero(grid.unknowns()), force = VecX::Zero(grid.unknowns());
  for (int k = 0; k <= 4; ++k)
    for (int j = 0; j <= 6; ++j)
      for (int d = 0; d < 3; ++d) fixed[3 * grid.node_index(0, j, k) + d] = 1;
  fixed[3 * grid.node_index(12, 3, 4) + 0] = 1;
  prescribed[3 * grid.node_index(12, 3, 4) + 0] = 0.01;
  for (int j = 0; j <= 6; ++j) force[3 * grid.node_index(12, j, 0) + 2] = -0.1;
  MatX pairs = MatX::Zero(grid.cells(), grid.voigt_pairs());
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (std::int64_t c = 0; c < grid.cells(); ++c) {
    const double E = 1e-6 + std::pow(u(rng), 3), l = E * 0.3 / (1.3 * 0.4), g = E / 2.6;
    for (int s = 0; s < 3; ++s) {
      for (int t = s; t < 3; ++t) pairs(c, CellGrid::pair_index(s, t, 6)) = s == t ? l + 2 * g : l;
      pairs(c, CellGrid::pair_index(3 + s, 3 + s, 6)) = g;
    }
  }
  LinearSolverOptions options;
  options.pcg_tolerance = 1e-11;
  options.mg_coarse_unknowns = 300;
  GridElasticity direct(grid, fixed, "cholmod", options), free(grid, fixed, "matrix-free", options);
  EXPECT_EQ(free.solver_name(), "matrix-free");
  direct.set_stiffness(pairs);
  free.set_stiffness(pairs);
  const VecX a = direct.solve(force, prescribed), b = free.solve(force, prescribed);
  EXPECT_LT((a - b).norm(), 1e-8 * a.norm());
  EXPECT_NEAR(direct.energy(a), free.energy(b), 1e-8 * direct.energy(a));
  EXPECT_THROW(GridElasticity(CellGrid(3, 5, 2, 2, 1.0), std::vector<char>(3 * 6 * 3 * 3, 0), "matrix-free", options),
               InputError);
}

}  // namespace
}  // namespace msfab
