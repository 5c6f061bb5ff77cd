// The Chebyshev smoother's operator stored by its upper blocks in single
// precision: its product must equal A's with every block rounded to float
// and the lower ones read from their mirrors, be exactly symmetric, and
// refuse a block pattern that is not symmetric.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <stdexcept>
#include <vector>

#include "solve/block_matrix.hpp"
#include "solve/chebyshev_smoother.hpp"
#include "solve/sparse_ops.hpp"

namespace msfab {
namespace {

// A symmetric positive definite matrix of n nodes with random 3x3 blocks
// between random node pairs (an irregular pattern, several blocks per row),
// made definite by a dominant diagonal; with `band`, pairs at most that
// many nodes apart (then about 4 per node).
SpMat random_spd_block_matrix(int nodes, unsigned seed, int band = 0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::uniform_int_distribution<int> node(0, nodes - 1);
  std::vector<Eigen::Triplet<double>> triplets;
  std::vector<double> row_sum(3 * std::size_t(nodes), 0.0);
  std::uniform_int_distribution<int> offset(1, std::max(band, 1));
  for (int pair = 0; pair < 4 * nodes; ++pair) {
    const int i = node(rng), j = band > 0 ? i + offset(rng) : node(rng);
    if (i == j || j >= nodes) continue;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const double v = value(rng);
        triplets.emplace_back(3 * i + a, 3 * j + b, v);
        triplets.emplace_back(3 * j + b, 3 * i + a, v);
        row_sum[3 * std::size_t(i) + a] += std::abs(v);
        row_sum[3 * std::size_t(j) + b] += std::abs(v);
      }
  }
  for (int u = 0; u < 3 * nodes; ++u) triplets.emplace_back(u, u, 1.0 + row_sum[std::size_t(u)]);
  SpMat A(3 * nodes, 3 * nodes);
  A.setFromTriplets(triplets.begin(), triplets.end());
  return A;
}

TEST(ChebyshevSmootherOperator, UpperBlocksInFloatReproduceTheRoundedProduct) {
  const int nodes = 3000;  // above the size where the row loops go parallel
  const SpMat A = random_spd_block_matrix(nodes, 7);
  BlockMatrix M = block_pattern(A);
  copy_block_values(A, 0.0, M, 1);
  ChebyshevSmoother smoother;
  ASSERT_TRUE(smoother.setup(M, 2, 2, SmootherValues::single_upper));

  // The reference: every upper block (and the diagonal) rounded to float,
  // every lower block the transpose of its rounded mirror.
  std::vector<Eigen::Triplet<double>> triplets;
  for (int k = 0; k < A.outerSize(); ++k)
    for (SpMat::InnerIterator it(A, k); it; ++it) {
      const int r = static_cast<int>(it.row()), c = static_cast<int>(it.col());
      if (r / 3 <= c / 3) triplets.emplace_back(r, c, double(static_cast<float>(it.value())));
      if (r / 3 < c / 3) triplets.emplace_back(c, r, double(static_cast<float>(it.value())));
    }
  SpMat rounded(A.rows(), A.cols());
  rounded.setFromTriplets(triplets.begin(), triplets.end());

  std::mt19937 rng(11);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  VecX x(A.rows()), y(A.rows()), zero = VecX::Zero(A.rows());
  for (Eigen::Index k = 0; k < x.size(); ++k) x[k] = value(rng), y[k] = value(rng);
  VecX minus_ax, minus_ay;
  smoother.residual(zero, x, minus_ax);  // 0 - A_s x
  smoother.residual(zero, y, minus_ay);
  const VecX expected = rounded * x;
  EXPECT_LE((minus_ax + expected).norm(), 1e-13 * expected.norm());
  // Exactly symmetric up to the round-off of the two dot products.
  EXPECT_NEAR(y.dot(minus_ax), x.dot(minus_ay), 1e-12 * std::abs(y.dot(minus_ax)));
  // And the rounding is a small change of A.
  EXPECT_LE((minus_ax + A * x).norm(), 1e-6 * (A * x).norm());
}

// A banded pattern (the lattice levels' shape) splits into many chunks of
// rows that run in parallel, two parities apart: the product is the
// rounded one and has the same bits on one and on three threads.
TEST(ChebyshevSmootherOperator, UpperProductByChunksIsTheSameOnAnyThreadCount) {
  const int nodes = 6000;
  const SpMat A = random_spd_block_matrix(nodes, 5, 37);
  BlockMatrix M = block_pattern(A);
  copy_block_values(A, 0.0, M, 1);
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  VecX x(A.rows()), zero = VecX::Zero(A.rows());
  for (Eigen::Index k = 0; k < x.size(); ++k) x[k] = value(rng);
  VecX minus_ax[2];
  for (int run = 0; run < 2; ++run) {
    ChebyshevSmoother smoother;
    ASSERT_TRUE(smoother.setup(M, 2, run == 0 ? 1 : 3, SmootherValues::single_upper));
    smoother.residual(zero, x, minus_ax[run]);
  }
  EXPECT_EQ(0, std::memcmp(minus_ax[0].data(), minus_ax[1].data(), sizeof(double) * std::size_t(x.size())));
  EXPECT_LE((minus_ax[0] + A * x).norm(), 1e-6 * (A * x).norm());

  // Smoothing (degree 3, from a non-zero start: every pass forms A x
  // first) equals the smoothing with every block in single precision, the
  // same rounded operator summed in another order.
  VecX smoothed[2];
  for (int run = 0; run < 2; ++run) {
    ChebyshevSmoother smoother;
    ASSERT_TRUE(smoother.setup(M, 3, 2, run == 0 ? SmootherValues::single_upper : SmootherValues::single));
    smoothed[run] = 0.5 * x;
    smoother.smooth(x, smoothed[run], false);
  }
  EXPECT_LE((smoothed[0] - smoothed[1]).norm(), 1e-12 * smoothed[1].norm());
  EXPECT_GT((smoothed[0] - 0.5 * x).norm(), 1e-3 * x.norm());  // the smoothing did something
}

TEST(ChebyshevSmootherOperator, RefusesAPatternThatIsNotSymmetric) {
  const SpMat A = random_spd_block_matrix(50, 3);
  BlockMatrix M = block_pattern(A);
  copy_block_values(A, 0.0, M, 1);
  // Drop the last block of the first row that has an off-diagonal block
  // above its diagonal: its mirror below the diagonal stays.
  for (int i = 0; i < M.rows; ++i) {
    const int last = M.row_start[std::size_t(i) + 1] - 1;
    if (last == M.diagonal[std::size_t(i)]) continue;
    M.column.erase(M.column.begin() + last);
    M.values.erase(M.values.begin() + 9 * std::ptrdiff_t(last), M.values.begin() + 9 * std::ptrdiff_t(last) + 9);
    for (int r = i + 1; r <= M.rows; ++r) --M.row_start[std::size_t(r)];
    for (int r = i + 1; r < M.rows; ++r) --M.diagonal[std::size_t(r)];
    break;
  }
  ChebyshevSmoother smoother;
  EXPECT_THROW(smoother.setup(M, 2, 1, SmootherValues::single_upper), std::logic_error);
  // The other kinds read A's blocks as stored and need no mirror.
  EXPECT_NO_THROW(smoother.setup(M, 2, 1, SmootherValues::single));
  EXPECT_NO_THROW(smoother.setup(M, 2, 1, SmootherValues::double_values));
}

}  // namespace
}  // namespace msfab
