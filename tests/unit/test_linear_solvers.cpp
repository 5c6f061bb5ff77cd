// Sparse linear solvers (common/solve): CHOLMOD and PCG against Eigen
// references, refactorization, inertia shift, determinism, failure modes.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <random>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "solve/cholmod_solver.hpp"
#include "solve/linear_solver.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {
namespace {

// B^T B + 0.1 I with B random and sparse (3 entries per row): SPD with a
// moderate condition number and an irregular pattern.
SpMat random_spd(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> column(0, n - 1);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::vector<Eigen::Triplet<double, int>> entries;
  for (int i = 0; i < n; ++i) {
    entries.emplace_back(i, i, 1.0 + value(rng));
    for (int k = 0; k < 2; ++k) entries.emplace_back(i, column(rng), value(rng));
  }
  SpMat B(n, n);
  B.setFromTriplets(entries.begin(), entries.end());
  SpMat identity(n, n);
  identity.setIdentity();
  SpMat A = SpMat(B.transpose()) * B + 0.1 * identity;
  A.makeCompressed();
  return A;
}

// Elasticity-like stiffness of a k^3 node grid, 3 unknowns per node: each
// pair of nodes in a 3x3x3 neighbourhood is joined by a spring-like block
// w (0.5 I + d d^T); nodes on the z = 0 face are held by a penalty. Its
// pattern is that of a trilinear hex mesh.
SpMat grid_stiffness(int k) {
  const int nodes = k * k * k;
  auto node = [k](int x, int y, int z) { return x + k * (y + k * z); };
  std::vector<Eigen::Triplet<double, int>> entries;
  for (int z = 0; z < k; ++z) {
    for (int y = 0; y < k; ++y) {
      for (int x = 0; x < k; ++x) {
        const int a = node(x, y, z);
        Mat3 diagonal = Mat3::Zero();
        if (z == 0) diagonal += Mat3::Identity();
        for (int dz = -1; dz <= 1; ++dz) {
          for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
              const int nx = x + dx, ny = y + dy, nz = z + dz;
              if ((dx == 0 && dy == 0 && dz == 0) || nx < 0 || ny < 0 || nz < 0 || nx >= k || ny >= k || nz >= k) {
                continue;
              }
              const Vec3 d = Vec3(dx, dy, dz).normalized();
              const Mat3 block = (0.5 * Mat3::Identity() + d * d.transpose()) / Vec3(dx, dy, dz).squaredNorm();
              diagonal += block;
              const int b = node(nx, ny, nz);
              for (int j = 0; j < 3; ++j) {
                for (int i = 0; i < 3; ++i) {
                  entries.emplace_back(3 * a + i, 3 * b + j, -block(i, j));
                }
              }
            }
          }
        }
        for (int j = 0; j < 3; ++j) {
          for (int i = 0; i < 3; ++i) entries.emplace_back(3 * a + i, 3 * a + j, diagonal(i, j));
        }
      }
    }
  }
  SpMat A(3 * nodes, 3 * nodes);
  A.setFromTriplets(entries.begin(), entries.end());
  A.makeCompressed();
  return A;
}

VecX random_vector(Eigen::Index n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  VecX v(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = value(rng);
  return v;
}

VecX sparse_reference_solve(const SpMat& A, const VecX& b) {
  Eigen::SimplicialLDLT<SpMat> ldlt(A);
  EXPECT_EQ(ldlt.info(), Eigen::Success);
  return ldlt.solve(b);
}

double relative_error(const VecX& x, const VecX& reference) { return (x - reference).norm() / reference.norm(); }

double eigen_residual(const SpMat& A, const VecX& x, const VecX& b) { return (b - A * x).norm() / b.norm(); }

LinearSolverOptions pcg_options(const std::string& preconditioner) {
  LinearSolverOptions options;
  options.pcg_preconditioner = preconditioner;
  return options;
}

TEST(LinearSolverCholmod, RandomSpdMatchesDenseLdlt) {
  const SpMat A = random_spd(300, 1);
  const VecX b = random_vector(A.rows(), 2);
  const VecX reference = MatX(A).ldlt().solve(b);
  auto solver = make_linear_solver("cholmod", {});
  EXPECT_EQ(solver->name(), "cholmod");
  solver->analyze(A);
  ASSERT_TRUE(solver->factorize(A));
  const VecX x = solver->solve(b);
  EXPECT_LT(relative_error(x, reference), 1e-8);
  EXPECT_TRUE(solver->stats().positive_definite);
  EXPECT_LT(solver->stats().relative_residual, 1e-12);
}

TEST(LinearSolverCholmod, GridStiffnessMatchesSimplicialLdltWithMetis) {
  const SpMat A = grid_stiffness(10);
  ASSERT_EQ(A.rows(), 3000);
  const VecX b = random_vector(A.rows(), 3);
  CholmodSolver solver;
  solver.analyze(A);
  EXPECT_EQ(solver.ordering(), "metis");
  EXPECT_GT(solver.factor_nonzeros(), 0.5 * A.nonZeros());
  ASSERT_TRUE(solver.factorize(A));
  const VecX x = solver.solve(b);
  EXPECT_LT(relative_error(x, sparse_reference_solve(A, b)), 1e-8);
  EXPECT_LT(eigen_residual(A, x, b), 1e-12);
}

// The contact solve's shortcut: with the given unknowns ordered last, the
// inverse's block on them comes from the factor's trailing block alone.
TEST(LinearSolverCholmod, TrailingFactorGivesTheInverseBlockOfTheLastUnknowns) {
  for (const SpMat& A : {random_spd(300, 12), grid_stiffness(6)}) {
    const int n = static_cast<int>(A.rows());
    const std::vector<int> last = {n - 1, 7, 3, n / 2, 11, n / 3};  // unsorted on purpose
    CholmodSolver solver;
    solver.analyze_with_last(A, last);
    EXPECT_EQ(solver.last_unknowns(), last);
    ASSERT_TRUE(solver.factorize(A));
    const MatX L = solver.trailing_factor();
    const MatX from_factor = (L * L.transpose()).inverse();
    const MatX inverse = MatX(A).inverse();
    MatX block(last.size(), last.size());
    for (std::size_t i = 0; i < last.size(); ++i)
      for (std::size_t j = 0; j < last.size(); ++j) block(i, j) = inverse(last[i], last[j]);
    EXPECT_LT((from_factor - block).norm(), 1e-10 * block.norm());
    // Solves stay those of A under the constrained ordering.
    const VecX b = VecX::LinSpaced(n, -1, 2);
    EXPECT_LT((A * solver.solve(b) - b).norm(), 1e-10 * b.norm());
    // analyze() gives the free ordering back.
    solver.analyze(A);
    EXPECT_TRUE(solver.last_unknowns().empty());
  }
  CholmodSolver solver;
  const SpMat A = random_spd(20, 1);
  EXPECT_THROW(solver.analyze_with_last(A, {3, 3}), InputError);
  EXPECT_THROW(solver.analyze_with_last(A, {20}), InputError);
}

TEST(LinearSolverPcg, RandomSpdResidualBelowTolerance) {
  const SpMat A = random_spd(300, 4);
  const VecX b = random_vector(A.rows(), 5);
  for (const std::string preconditioner : {"jacobi", "block-jacobi3"}) {
    auto solver = make_linear_solver("pcg", pcg_options(preconditioner));
    EXPECT_EQ(solver->name(), "pcg");
    solver->analyze(A);
    ASSERT_TRUE(solver->factorize(A)) << preconditioner;
    const VecX x = solver->solve(b);
    EXPECT_LE(eigen_residual(A, x, b), 1e-8 * (1 + 1e-6)) << preconditioner;
    EXPECT_LE(solver->stats().relative_residual, 1e-8) << preconditioner;
    EXPECT_GT(solver->stats().iterations, 1) << preconditioner;
  }
}

TEST(LinearSolverPcg, GridStiffnessResidualBelowTolerance) {
  const SpMat A = grid_stiffness(10);
  const VecX b = random_vector(A.rows(), 6);
  const VecX reference = sparse_reference_solve(A, b);
  int jacobi_iterations = 0;
  for (const std::string preconditioner : {"jacobi", "block-jacobi3"}) {
    auto solver = make_linear_solver("pcg", pcg_options(preconditioner));
    solver->analyze(A);
    ASSERT_TRUE(solver->factorize(A)) << preconditioner;
    const VecX x = solver->solve(b);
    EXPECT_LE(eigen_residual(A, x, b), 1e-8 * (1 + 1e-6)) << preconditioner;
    EXPECT_LT(relative_error(x, reference), 1e-5) << preconditioner;
    if (preconditioner == "jacobi") {
      jacobi_iterations = solver->stats().iterations;
    } else {
      // The node blocks hold the strong x-y-z coupling of each node.
      EXPECT_LE(solver->stats().iterations, jacobi_iterations) << preconditioner;
    }
  }
}

TEST(LinearSolver, RefactorizeNewValuesOnSamePattern) {
  const SpMat A = grid_stiffness(6);
  const VecX b = random_vector(A.rows(), 7);
  for (const std::string name : {"cholmod", "pcg"}) {
    auto solver = make_linear_solver(name, {});
    solver->analyze(A);
    for (int round = 0; round < 3; ++round) {
      // New values, same pattern: scale and change the diagonal.
      SpMat A_round = A * (1.0 + round);
      const VecX extra = random_vector(A.rows(), 10 + round).cwiseAbs();
      for (Eigen::Index i = 0; i < A.rows(); ++i) A_round.coeffRef(i, i) += extra[i];
      // Uncompressed storage (gaps after columns) must be read correctly too.
      if (round == 2) A_round.uncompress();
      ASSERT_EQ(A_round.isCompressed(), round != 2);
      ASSERT_TRUE(solver->factorize(A_round)) << name << " round " << round;
      const VecX x = solver->solve(b);
      const VecX reference = sparse_reference_solve(A_round, b);
      EXPECT_LT(relative_error(x, reference), name == "cholmod" ? 1e-8 : 1e-5) << name << " round " << round;
      EXPECT_LE(eigen_residual(A_round, x, b), 1e-8 * (1 + 1e-6)) << name << " round " << round;
    }
    // A different pattern must be rejected rather than silently misused.
    const SpMat other = random_spd(static_cast<int>(A.rows()), 8);
    EXPECT_THROW(solver->factorize(other), std::invalid_argument) << name;
  }
}

TEST(LinearSolverCholmod, IndefiniteRejectedThenShiftSucceeds) {
  const SpMat spd = random_spd(300, 9);
  const Eigen::SelfAdjointEigenSolver<MatX> spectrum(MatX(spd), Eigen::EigenvaluesOnly);
  const double lowest = spectrum.eigenvalues()(0);
  const double middle = spectrum.eigenvalues()(150);
  SpMat identity(spd.rows(), spd.cols());
  identity.setIdentity();
  // Negative eigenvalues down to lowest - middle < 0.
  const SpMat A = spd - middle * identity;
  const VecX b = random_vector(A.rows(), 10);

  CholmodSolver solver;
  solver.analyze(A);
  EXPECT_FALSE(solver.factorize(A));
  EXPECT_FALSE(solver.stats().positive_definite);
  EXPECT_THROW(solver.solve(b), NumericalError);

  // A shift just short of the most negative eigenvalue still fails ...
  const double needed = middle - lowest;
  EXPECT_FALSE(solver.factorize(A, 0.9 * needed));
  // ... and one past it succeeds and solves (A + shift I) x = b.
  const double shift = needed + 1.0;
  ASSERT_TRUE(solver.factorize(A, shift));
  EXPECT_TRUE(solver.stats().positive_definite);
  const VecX x = solver.solve(b);
  const MatX shifted = MatX(A) + shift * MatX::Identity(A.rows(), A.cols());
  EXPECT_LT(relative_error(x, shifted.ldlt().solve(b)), 1e-8);
}

// With `indefinite`, CHOLMOD factors L D L^T: the solve matches a pivoted
// dense one and the negative pivots are the negative eigenvalues (Sylvester);
// a zero pivot still fails.
TEST(LinearSolverCholmod, IndefiniteLdltSolvesAndCountsNegativeEigenvalues) {
  const SpMat spd = random_spd(300, 9);
  const Eigen::SelfAdjointEigenSolver<MatX> spectrum(MatX(spd), Eigen::EigenvaluesOnly);
  // Between the 100th and 101st eigenvalues: exactly 100 negative ones.
  const double cut = 0.5 * (spectrum.eigenvalues()(99) + spectrum.eigenvalues()(100));
  SpMat identity(spd.rows(), spd.cols());
  identity.setIdentity();
  const SpMat A = spd - cut * identity;
  const VecX b = random_vector(A.rows(), 10);

  LinearSolverOptions options;
  options.indefinite = true;
  CholmodSolver solver(options);
  solver.analyze(A);
  ASSERT_TRUE(solver.factorize(A));
  EXPECT_EQ(solver.negative_pivots(), 100);
  EXPECT_FALSE(solver.stats().positive_definite);
  const VecX x = solver.solve(b);
  EXPECT_LT(relative_error(x, MatX(A).fullPivLu().solve(b)), 1e-8);
  EXPECT_LT(solver.stats().relative_residual, 1e-10);

  // Positive definite: no negative pivot, the L L^T solution.
  ASSERT_TRUE(solver.factorize(spd));
  EXPECT_EQ(solver.negative_pivots(), 0);
  EXPECT_TRUE(solver.stats().positive_definite);
  CholmodSolver ll;
  ll.analyze(spd);
  ASSERT_TRUE(ll.factorize(spd));
  EXPECT_LT(relative_error(solver.solve(b), ll.solve(b)), 1e-10);

  // A zero pivot: the second unknown decoupled with a zero diagonal.
  std::vector<Eigen::Triplet<double, int>> entries{{0, 0, 2.0}, {1, 1, 0.0}, {2, 2, -3.0}, {2, 0, 1.0}, {0, 2, 1.0}};
  SpMat singular(3, 3);
  singular.setFromTriplets(entries.begin(), entries.end());
  CholmodSolver zero(options);
  zero.analyze(singular);
  EXPECT_FALSE(zero.factorize(singular));
  EXPECT_THROW(zero.solve(VecX::Ones(3)), NumericalError);
}

TEST(LinearSolverPcg, NegativeDiagonalRejectedThenShiftSucceeds) {
  const SpMat spd = grid_stiffness(4);
  SpMat identity(spd.rows(), spd.cols());
  identity.setIdentity();
  const double largest_diagonal = VecX(spd.diagonal()).maxCoeff();
  const SpMat A = spd - 2.0 * largest_diagonal * identity;
  const VecX b = random_vector(A.rows(), 11);
  for (const std::string preconditioner : {"jacobi", "block-jacobi3"}) {
    auto solver = make_linear_solver("pcg", pcg_options(preconditioner));
    solver->analyze(A);
    EXPECT_FALSE(solver->factorize(A)) << preconditioner;
    EXPECT_THROW(solver->solve(b), NumericalError) << preconditioner;
    const double shift = 2.0 * largest_diagonal;
    ASSERT_TRUE(solver->factorize(A, shift)) << preconditioner;
    const VecX x = solver->solve(b);
    EXPECT_LE(eigen_residual(spd, x, b), 1e-8 * (1 + 1e-6)) << preconditioner;
  }
}

TEST(LinearSolverPcg, BitwiseIdenticalForOneAndTwoThreads) {
  const int saved_threads = omp_get_max_threads();
  // Several reduction chunks, so the partial sums really are split.
  const SpMat A = grid_stiffness(14);
  ASSERT_GT(A.rows(), 2 * kReductionChunk);
  const VecX b = random_vector(A.rows(), 12);
  for (const std::string preconditioner : {"jacobi", "block-jacobi3"}) {
    std::vector<VecX> solutions;
    std::vector<LinearSolveStats> stats;
    for (int threads : {1, 2}) {
      omp_set_num_threads(threads);
      auto solver = make_linear_solver("pcg", pcg_options(preconditioner));
      solver->analyze(A);
      ASSERT_TRUE(solver->factorize(A, 1.0));
      solutions.push_back(solver->solve(b));
      stats.push_back(solver->stats());
    }
    omp_set_num_threads(saved_threads);
    EXPECT_EQ(stats[0].iterations, stats[1].iterations) << preconditioner;
    EXPECT_EQ(stats[0].relative_residual, stats[1].relative_residual) << preconditioner;
    ASSERT_EQ(solutions[0].size(), solutions[1].size());
    Eigen::Index differing = 0;
    for (Eigen::Index i = 0; i < solutions[0].size(); ++i) {
      if (solutions[0][i] != solutions[1][i]) ++differing;
    }
    EXPECT_EQ(differing, 0) << preconditioner;
  }
  // Reductions themselves: a long dot product whose sum order matters.
  const VecX u = random_vector(20 * kReductionChunk + 17, 13);
  const VecX v = random_vector(u.size(), 14);
  EXPECT_EQ(parallel_dot(u, v, 1), parallel_dot(u, v, 2));
  EXPECT_NEAR(parallel_dot(u, v, 2), u.dot(v), 1e-10 * u.size());
}

TEST(LinearSolverPcg, ThrowsWhenMaxIterationsTooSmall) {
  const SpMat A = grid_stiffness(8);
  const VecX b = random_vector(A.rows(), 15);
  LinearSolverOptions options;
  options.pcg_max_iterations = 5;
  auto solver = make_linear_solver("pcg", options);
  solver->analyze(A);
  ASSERT_TRUE(solver->factorize(A));
  try {
    solver->solve(b);
    FAIL() << "PCG converged in 5 iterations on a 1536-unknown stiffness matrix";
  } catch (const NumericalError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("5 iterations"), std::string::npos) << message;
    EXPECT_NE(message.find("relative residual"), std::string::npos) << message;
    // No config key set this limit: none is named.
    EXPECT_NE(message.find("iteration limit 5)"), std::string::npos) << message;
    EXPECT_EQ(message.find("pcg_max_iterations"), std::string::npos) << message;
  }
  EXPECT_EQ(solver->stats().iterations, 5);
  EXPECT_GT(solver->stats().relative_residual, 1e-8);
  // Read from a config: the message names the key to raise.
  options.pcg_max_iterations_key = "scene.yaml: solver.pcg_max_iterations";
  auto keyed = make_linear_solver("pcg", options);
  keyed->analyze(A);
  ASSERT_TRUE(keyed->factorize(A));
  try {
    keyed->solve(b);
    FAIL() << "PCG converged in 5 iterations";
  } catch (const NumericalError& error) {
    EXPECT_NE(std::string(error.what()).find("iteration limit 5 set by scene.yaml: solver.pcg_max_iterations"),
              std::string::npos)
        << error.what();
  }
}

TEST(LinearSolver, EmptySystemSolvesToEmptyVector) {
  const SpMat empty(0, 0);
  for (const std::string& name : linear_solver_names()) {
    auto solver = make_linear_solver(name, {});
    solver->analyze(empty);
    ASSERT_TRUE(solver->factorize(empty)) << name;
    EXPECT_EQ(solver->solve(VecX()).size(), 0) << name;
  }
}

TEST(LinearSolverFactory, UnknownNameThrowsInputErrorListingValidNames) {
  try {
    make_linear_solver("superlu", {});
    FAIL() << "an unknown solver name was accepted";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("superlu"), std::string::npos) << message;
    EXPECT_NE(message.find("cholmod"), std::string::npos) << message;
    EXPECT_NE(message.find("pcg"), std::string::npos) << message;
  }
  EXPECT_THROW(make_linear_solver("pcg", pcg_options("ilu")), InputError);
  LinearSolverOptions zero_tolerance;
  zero_tolerance.pcg_tolerance = 0.0;
  EXPECT_THROW(make_linear_solver("pcg", zero_tolerance), InputError);
}

}  // namespace
}  // namespace msfab
