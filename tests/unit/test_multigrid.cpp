// Geometric multigrid-preconditioned CG ("pcg-mg") on voxel-mesh elasticity:
// agreement with CHOLMOD, mesh-independent iteration counts, the Galerkin
// operator and V-cycle symmetry, determinism, the shift, input errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "fem/elastic_assembler.hpp"
#include "fem/voxel_grid.hpp"
#include "material/neo_hookean.hpp"
#include "solve/cholmod_solver.hpp"
#include "solve/linear_solver.hpp"
#include "solve/multigrid_solver.hpp"
#include "solve/newton.hpp"
#include "solve/node_lattice.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {
namespace {

// Rest-state stiffness of an n^3 voxel cube: soft matrix (E = 1e5) with a
// stiff cylinder and a stiff slab (E = 1e7), nu = 0.45, a void tunnel and a
// void corner; the y = 0 face is clamped the way Newton's method does it
// (rows and columns cleared, a positive diagonal kept).
struct VoxelStiffness {
  VoxelMesh voxels;
  SpMat K;
  std::vector<char> fixed;
  std::shared_ptr<const NodeArray> nodes;
  VecX load;
};

std::unique_ptr<VoxelStiffness> voxel_stiffness(int n, int clamped_layers = 1) {
  VoxelGrid grid(n, n, n, 1.0 / n, 1);
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < n; ++j) {
      for (int i = 0; i < n; ++i) {
        const double x = (i + 0.5) / n, y = (j + 0.5) / n, z = (k + 0.5) / n;
        const bool tunnel = std::abs(x - 0.25) < 0.125 && std::abs(z - 0.75) < 0.125;
        const bool corner = x > 0.75 && y > 0.75 && z < 0.5;
        const bool cylinder = std::hypot(x - 0.6, z - 0.4) < 0.2;
        const bool slab = y > 0.4 && y < 0.55;
        grid.at(i, j, k) = (tunnel || corner) ? 0 : (cylinder || slab) ? 2 : 1;
      }
    }
  }
  const std::vector<MaterialPtr> palette = {nullptr, std::make_shared<NeoHookean>(1e5, 0.45),
                                            std::make_shared<NeoHookean>(1e7, 0.45)};
  auto problem = std::make_unique<VoxelStiffness>();
  problem->voxels = build_voxel_mesh(grid, palette);
  const HexMesh& mesh = problem->voxels.mesh;
  const ElasticAssembler assembler(mesh);
  problem->K = assembler.pattern();
  assembler.evaluate(assembler.rest_positions(), nullptr, &problem->K);

  const int dofs = mesh.num_dofs();
  problem->fixed.assign(static_cast<std::size_t>(dofs), 0);
  for (int node = 0; node < mesh.num_nodes(); ++node) {
    if (mesh.nodes(node, 1) < (clamped_layers - 0.5) / n) {
      for (int a = 0; a < 3; ++a) problem->fixed[static_cast<std::size_t>(3 * node + a)] = 1;
    }
  }
  double diagonal_sum = 0.0;
  int free_count = 0;
  for (int c = 0; c < dofs; ++c) {
    if (problem->fixed[static_cast<std::size_t>(c)]) continue;
    diagonal_sum += problem->K.coeff(c, c);
    ++free_count;
  }
  const double diagonal = diagonal_sum / free_count;
  for (int c = 0; c < problem->K.outerSize(); ++c) {
    for (SpMat::InnerIterator it(problem->K, c); it; ++it) {
      const auto r = static_cast<std::size_t>(it.row());
      if (problem->fixed[static_cast<std::size_t>(c)] || problem->fixed[r]) {
        it.valueRef() = (it.row() == c) ? diagonal : 0.0;
      }
    }
  }
  problem->nodes = std::make_shared<const NodeArray>(mesh.nodes);

  // A body force with a random part, so every mode is excited; the clamped
  // unknowns get a prescribed value too.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> noise(-1.0, 1.0);
  problem->load.resize(dofs);
  for (int i = 0; i < dofs; ++i) {
    problem->load[i] = (i % 3 == 2 ? -1.0 : 0.0) + 0.5 * noise(rng);
    if (problem->fixed[static_cast<std::size_t>(i)]) problem->load[i] = 1e-3 * diagonal * noise(rng);
  }
  return problem;
}

LinearSolverOptions multigrid_options(const VoxelStiffness& problem, double tolerance, int coarse_unknowns = 3000) {
  LinearSolverOptions options;
  options.node_positions = problem.nodes;
  options.pcg_tolerance = tolerance;
  options.pcg_max_iterations = 200;
  options.mg_coarse_unknowns = coarse_unknowns;
  return options;
}

VecX cholmod_solution(const SpMat& K, const VecX& b, double shift = 0.0) {
  CholmodSolver direct;
  direct.analyze(K);
  EXPECT_TRUE(direct.factorize(K, shift));
  return direct.solve(b);
}

TEST(MultigridSolver, MatchesCholmodOnTwoMaterialVoxelMeshWithVoids) {
  const auto problem = voxel_stiffness(16);
  auto solver = make_linear_solver("pcg-mg", multigrid_options(*problem, 1e-10));
  solver->analyze(problem->K);
  ASSERT_TRUE(solver->factorize(problem->K));
  const VecX x = solver->solve(problem->load);
  const VecX reference = cholmod_solution(problem->K, problem->load);
  const double error = (x - reference).norm() / reference.norm();
  const int levels = dynamic_cast<MultigridSolver&>(*solver).num_levels();
  std::printf(
      "[ pcg-mg   ] 16^3 voxels, %ld unknowns, %d levels: %d iterations, "
      "relative error vs CHOLMOD %.2e\n",
      static_cast<long>(problem->K.rows()), levels, solver->stats().iterations, error);
  EXPECT_GE(levels, 2);
  EXPECT_LT(error, 1e-6);
  EXPECT_LT(solver->stats().iterations, 60);
  EXPECT_LE(solver->stats().relative_residual, 1e-10);
  EXPECT_LE(relative_residual(problem->K, x, problem->load), 1e-10);
  EXPECT_TRUE(solver->stats().positive_definite);
}

TEST(MultigridSolver, IterationCountIsNearlyMeshIndependent) {
  std::vector<int> iterations;
  for (int n : {8, 16, 32}) {
    const auto problem = voxel_stiffness(n);
    // The same coarsest lattice (5^3 points) for every mesh.
    MultigridSolver solver(multigrid_options(*problem, 1e-8, 500));
    solver.analyze(problem->K);
    ASSERT_TRUE(solver.factorize(problem->K));
    solver.solve(problem->load);
    iterations.push_back(solver.stats().iterations);
    std::printf(
        "[ pcg-mg   ] %d^3 voxels, %ld unknowns, %d levels: %d iterations "
        "(factorize %.3f s, solve %.3f s)\n",
        n, static_cast<long>(problem->K.rows()), solver.num_levels(), solver.stats().iterations,
        solver.stats().factorize_seconds, solver.stats().solve_seconds);
    EXPECT_LE(solver.stats().relative_residual, 1e-8);
  }
  const int low = *std::min_element(iterations.begin(), iterations.end());
  const int high = *std::max_element(iterations.begin(), iterations.end());
  EXPECT_LT(high, 2 * low);
}

TEST(MultigridGalerkin, CoarseOperatorIsPTransposeAPAndSymmetric) {
  // Two clamped node layers: the coarse nodes on y = 0 interpolate only to
  // clamped fine unknowns, so P has empty columns there.
  const auto problem = voxel_stiffness(12, 2);
  MultigridSolver solver(multigrid_options(*problem, 1e-8, 500));
  solver.analyze(problem->K);
  const double shift = 3.0;
  ASSERT_TRUE(solver.factorize(problem->K, shift));
  ASSERT_GE(solver.num_levels(), 3);
  for (int level = 0; level + 1 < solver.num_levels(); ++level) {
    const SpMat fine = solver.level_operator(level);
    const SpMat P = solver.prolongation(level);
    const SpMat expected = SpMat(P.transpose()) * fine * P;
    const SpMat coarse = solver.level_operator(level + 1);
    SpMat difference = coarse - expected;
    // Coarse unknowns that P does not reach carry a unit diagonal instead of 0.
    int unreached = 0;
    for (int c = 0; c < P.cols(); ++c) {
      if (P.col(c).nonZeros() > 0) continue;
      difference.coeffRef(c, c) -= 1.0;
      ++unreached;
    }
    if (level == 0) {
      EXPECT_GT(unreached, 0);
    }
    EXPECT_LT(difference.norm(), 1e-12 * expected.norm()) << "level " << level;
    EXPECT_EQ(SpMat(coarse - SpMat(coarse.transpose())).norm(), 0.0) << "level " << level;
    if (level == 0) {
      // Level 0 is K + shift I.
      SpMat shifted = problem->K;
      for (int i = 0; i < shifted.rows(); ++i) shifted.coeffRef(i, i) += shift;
      EXPECT_EQ(SpMat(fine - shifted).norm(), 0.0);
    }
    // Trilinear interpolation reproduces constants: each row of P sums to 1,
    // except for decoupled unknowns (clamped ones on level 0, unreached ones
    // below), whose rows are empty.
    const VecX row_sums = P * VecX::Ones(P.cols());
    for (Eigen::Index i = 0; i < P.rows(); ++i) {
      bool coupled = false;
      for (SpMat::InnerIterator it(fine, i); it; ++it) coupled |= it.row() != i && it.value() != 0;
      if (level == 0) {
        ASSERT_EQ(coupled, !problem->fixed[static_cast<std::size_t>(i)]) << "row " << i;
      }
      ASSERT_DOUBLE_EQ(row_sums[i], coupled ? 1.0 : 0.0) << "level " << level << " row " << i;
    }
  }
  // The decoupled coarse unknowns do not disturb the solve.
  const VecX x = solver.solve(problem->load);
  EXPECT_LE(relative_residual(problem->K, x, problem->load, shift), 1e-8);
  EXPECT_LT(solver.stats().iterations, 60);
}

TEST(MultigridPreconditioner, VCycleIsSymmetricPositiveDefinite) {
  const auto problem = voxel_stiffness(12);
  MultigridSolver solver(multigrid_options(*problem, 1e-8, 500));
  solver.analyze(problem->K);
  ASSERT_TRUE(solver.factorize(problem->K));
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  const Eigen::Index n = problem->K.rows();
  for (int trial = 0; trial < 3; ++trial) {
    VecX x(n), y(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      x[i] = normal(rng);
      y[i] = normal(rng);
    }
    const VecX mx = solver.apply_preconditioner(x);
    const VecX my = solver.apply_preconditioner(y);
    const double scale = std::sqrt(mx.dot(x) * my.dot(y));
    EXPECT_GT(mx.dot(x), 0.0);
    EXPECT_LT(std::abs(mx.dot(y) - x.dot(my)), 1e-10 * scale);
  }
}

TEST(MultigridDeterminism, BitwiseIdenticalWithOneAndTwoThreads) {
  const auto problem = voxel_stiffness(16);
  VecX solutions[2];
  int iterations[2] = {0, 0};
  for (int threads : {1, 2}) {
    LinearSolverOptions options = multigrid_options(*problem, 1e-8);
    options.threads = threads;
    MultigridSolver solver(options);
    solver.analyze(problem->K);
    ASSERT_TRUE(solver.factorize(problem->K, 1.0));
    solutions[threads - 1] = solver.solve(problem->load);
    iterations[threads - 1] = solver.stats().iterations;
  }
  EXPECT_EQ(iterations[0], iterations[1]);
  ASSERT_EQ(solutions[0].size(), solutions[1].size());
  EXPECT_TRUE((solutions[0].array() == solutions[1].array()).all());
}

TEST(MultigridShift, SolvesTheShiftedSystem) {
  const auto problem = voxel_stiffness(12);
  MultigridSolver solver(multigrid_options(*problem, 1e-10));
  solver.analyze(problem->K);
  const double shift = 0.05 * problem->K.diagonal().mean();
  ASSERT_TRUE(solver.factorize(problem->K, shift));
  const VecX x = solver.solve(problem->load);
  EXPECT_LE(relative_residual(problem->K, x, problem->load, shift), 1e-10);
  const VecX reference = cholmod_solution(problem->K, problem->load, shift);
  EXPECT_LT((x - reference).norm(), 1e-6 * reference.norm());
  // The shift matters: the unshifted solution is far from this one.
  const VecX unshifted = cholmod_solution(problem->K, problem->load);
  EXPECT_GT((x - unshifted).norm(), 1e-2 * unshifted.norm());

  // Refactorizing with another shift on the same pattern works too.
  ASSERT_TRUE(solver.factorize(problem->K, 0.0));
  EXPECT_LT((solver.solve(problem->load) - unshifted).norm(), 1e-6 * unshifted.norm());
}

TEST(MultigridSolver, NegativeShiftIsReportedNotPositiveDefinite) {
  const auto problem = voxel_stiffness(8);
  MultigridSolver solver(multigrid_options(*problem, 1e-8, 100));
  solver.analyze(problem->K);
  EXPECT_FALSE(solver.factorize(problem->K, -2.0 * problem->K.diagonal().maxCoeff()));
  EXPECT_FALSE(solver.stats().positive_definite);
  EXPECT_THROW(solver.solve(problem->load), NumericalError);
}

TEST(MultigridSolver, NonConvergenceThrowsWithIterationsAndResidual) {
  const auto problem = voxel_stiffness(8);
  LinearSolverOptions options = multigrid_options(*problem, 1e-12, 100);
  options.pcg_max_iterations = 2;
  MultigridSolver solver(options);
  solver.analyze(problem->K);
  ASSERT_TRUE(solver.factorize(problem->K));
  try {
    solver.solve(problem->load);
    FAIL() << "two iterations reached a 1e-12 residual";
  } catch (const NumericalError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("2 iterations"), std::string::npos) << message;
    EXPECT_NE(message.find("relative residual"), std::string::npos) << message;
  }
  EXPECT_EQ(solver.stats().iterations, 2);
  EXPECT_GT(solver.stats().relative_residual, 1e-12);
}

TEST(MultigridInput, MissingOrBadGeometryThrowsInputError) {
  const auto problem = voxel_stiffness(4);
  auto expect_input_error = [&](const LinearSolverOptions& options, const std::string& detail) {
    auto solver = make_linear_solver("pcg-mg", options);
    try {
      solver->analyze(problem->K);
      FAIL() << "accepted: " << detail;
    } catch (const InputError& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find("pcg-mg needs a voxel mesh"), std::string::npos) << message;
      EXPECT_NE(message.find(detail), std::string::npos) << message;
    }
  };
  expect_input_error(LinearSolverOptions{}, "node_positions");

  LinearSolverOptions off_lattice = multigrid_options(*problem, 1e-8);
  NodeArray moved = *problem->nodes;
  moved(5, 0) += 0.3 * (1.0 / 4);
  off_lattice.node_positions = std::make_shared<const NodeArray>(moved);
  expect_input_error(off_lattice, "off the regular lattice");

  LinearSolverOptions too_few = multigrid_options(*problem, 1e-8);
  too_few.node_positions = std::make_shared<const NodeArray>(problem->nodes->topRows(problem->nodes->rows() - 1));
  expect_input_error(too_few, "rows");

  // Nodes on a lattice, but not in the matrix's order: the matrix then
  // couples nodes farther apart on the lattice than any hex mesh does (up to
  // GridTransfer::kMaxCouplingSteps for elements of mixed sizes). A 12^3
  // mesh, so that the lattice is wider than that.
  const auto larger = voxel_stiffness(12);
  LinearSolverOptions shuffled = multigrid_options(*larger, 1e-8, 3);
  std::vector<int> order(static_cast<std::size_t>(larger->nodes->rows()));
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937(3));
  NodeArray permuted(larger->nodes->rows(), 3);
  for (std::size_t i = 0; i < order.size(); ++i) {
    permuted.row(static_cast<Eigen::Index>(i)) = larger->nodes->row(order[i]);
  }
  shuffled.node_positions = std::make_shared<const NodeArray>(permuted);
  {
    MultigridSolver solver(shuffled);
    try {
      solver.analyze(larger->K);
      FAIL() << "accepted a shuffled node order";
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find("not neighbours"), std::string::npos) << error.what();
    }
  }

  EXPECT_THROW(make_linear_solver("pcg-mg", multigrid_options(*problem, 1e-8, 0)), InputError);
}

TEST(MultigridNewton, LargeStretchMatchesCholmod) {
  // A two-material bar clamped at y = 0 and pulled and sheared at the top.
  VoxelGrid grid(4, 10, 4, 0.1, 1);
  for (int j = 0; j < 10; ++j) {
    for (int i = 1; i < 3; ++i) grid.at(i, j, 1) = 2;
  }
  grid.at(0, 5, 0) = 0;
  const std::vector<MaterialPtr> palette = {nullptr, std::make_shared<NeoHookean>(1e5, 0.45),
                                            std::make_shared<NeoHookean>(1e7, 0.45)};
  const VoxelMesh voxels = build_voxel_mesh(grid, palette);
  const HexMesh& mesh = voxels.mesh;
  const ElasticAssembler assembler(mesh);
  DirichletConditions dirichlet = DirichletConditions::none(mesh.num_dofs());
  for (int node = 0; node < mesh.num_nodes(); ++node) {
    const double y = mesh.nodes(node, 1);
    if (y > 1e-9 && y < 1.0 - 1e-9) continue;
    for (int a = 0; a < 3; ++a) dirichlet.fixed[static_cast<std::size_t>(3 * node + a)] = 1;
    if (y > 0.5) {
      dirichlet.displacement[3 * node + 1] = 0.3;
      dirichlet.displacement[3 * node + 0] = 0.1;
    }
  }
  const VecX force = VecX::Zero(mesh.num_dofs());
  NewtonOptions options;
  options.relative_tolerance = 1e-9;
  options.load_steps = 2;
  const NewtonResult direct = solve_static(assembler, dirichlet, force, options);
  ASSERT_TRUE(direct.converged) << direct.failure;

  options.linear_solver = "pcg-mg";
  options.linear.node_positions = std::make_shared<const NodeArray>(mesh.nodes);
  options.linear.pcg_tolerance = 1e-10;
  options.linear.mg_coarse_unknowns = 200;
  const NewtonResult multigrid = solve_static(assembler, dirichlet, force, options);
  ASSERT_TRUE(multigrid.converged) << multigrid.failure;
  int linear_iterations = 0;
  for (const NewtonIteration& step : multigrid.history) {
    linear_iterations = std::max(linear_iterations, step.linear_iterations);
  }
  std::printf("[ pcg-mg   ] Newton: %d iterations (CHOLMOD: %d), at most %d CG iterations each\n", multigrid.iterations,
              direct.iterations, linear_iterations);
  EXPECT_LT((multigrid.x - direct.x).norm(), 1e-7 * direct.x.norm());
  EXPECT_GT(linear_iterations, 1);
  EXPECT_LT(linear_iterations, 60);
}

TEST(MultigridLattice, CoarseningKeepsPointsNextToFineNodes) {
  // Nodes at x = 0..4 on a line plus one isolated node at x = 8.
  NodePositions positions(6, 3);
  for (int i = 0; i < 5; ++i) positions.row(i) << 0.5 * i, 1.0, 2.0;
  positions.row(5) << 4.0, 1.0, 2.0;
  const NodeLattice fine = lattice_from_positions(positions);
  EXPECT_EQ(fine.dims[0], 9);
  EXPECT_EQ(fine.dims[1], 1);
  EXPECT_EQ(fine.node(8, 0, 0), 5);
  EXPECT_EQ(fine.node(6, 0, 0), -1);
  const NodeLattice coarse = coarsen_lattice(fine);
  // Coarse points 0, 1, 2 (fine 0, 2, 4) and 4 (fine 8); point 3 (fine 6)
  // has no fine node within one spacing.
  ASSERT_EQ(coarse.num_nodes(), 4);
  EXPECT_EQ(coarse.node(3, 0, 0), -1);
  EXPECT_EQ(coarse.node(4, 0, 0), 3);
}

}  // namespace
}  // namespace msfab
