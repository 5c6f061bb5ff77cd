// Family discovery numerics: aligned structure distance, Isomap, Gaussian
// mixtures with BIC.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "core/errors.hpp"
#include "families/gaussian_mixture.hpp"
#include "families/isomap.hpp"
#include "families/structure_distance.hpp"

namespace msfab {
namespace {

constexpr double kEmbeddingPi = 3.14159265358979323846;

double uniform(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

// Box-Muller from raw engine output, so the data do not depend on the
// standard library's normal_distribution.
double gaussian(std::mt19937_64& rng) {
  const double u = 1.0 - uniform(rng), v = uniform(rng);
  return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * kEmbeddingPi * v);
}

std::vector<int> random_ids(int n, double solid_fraction, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<int> ids(std::size_t(n) * n * n);
  for (int& id : ids) id = uniform(rng) < solid_fraction ? 1 : 0;
  return ids;
}

VoxelField embedding_random_field(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  VoxelField f(n);
  for (Eigen::Index v = 0; v < f.values.size(); ++v) f.values[v] = uniform(rng);
  return f;
}

// Three orthogonal cylinders of radius r through the cell centre: a
// one-parameter family of cubic-symmetric beam structures.
std::vector<int> beam_cross(int n, double r) {
  std::vector<int> ids(std::size_t(n) * n * n, 0);
  const double c = 0.5 * n;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double x = i + 0.5 - c, y = j + 0.5 - c, z = k + 0.5 - c;
        const bool solid = x * x + y * y <= r * r || y * y + z * z <= r * r || x * x + z * z <= r * r;
        ids[std::size_t(i) + std::size_t(n) * (j + std::size_t(n) * k)] = solid ? 1 : 0;
      }
  return ids;
}

double brute_force_distance(const VoxelField& a, const VoxelField& b, std::array<int, 3>* argmin) {
  double best = -1;
  for (int tz = 0; tz < a.n; ++tz)
    for (int ty = 0; ty < a.n; ++ty)
      for (int tx = 0; tx < a.n; ++tx) {
        const VoxelField s = translate_field(b, {{tx, ty, tz}});
        const double d = std::sqrt((a.values - s.values).squaredNorm() / double(a.values.size()));
        if (best < 0 || d < best) best = d, *argmin = {{tx, ty, tz}};
      }
  return best;
}

MatX euclidean_distances(const MatX& X) {
  MatX D(X.rows(), X.rows());
  for (Eigen::Index i = 0; i < X.rows(); ++i)
    for (Eigen::Index j = 0; j < X.rows(); ++j) D(i, j) = (X.row(i) - X.row(j)).norm();
  return D;
}

// ---------------------------------------------------------------- distance

TEST(StructureDistance, TranslateIsAtZeroDistanceAndTheShiftIsRecovered) {
  const VoxelField b = smoothed_field(random_ids(16, 0.3, 1), 16);
  for (const std::array<int, 3>& t : {std::array<int, 3>{{3, 7, 12}}, std::array<int, 3>{{0, 0, 5}}}) {
    const VoxelField a = translate_field(b, t);
    EXPECT_GT((a.values - b.values).norm(), 1.0);  // the translate really differs voxel by voxel
    const AlignedDistance d = structure_distance(a, b);
    EXPECT_LT(d.distance, 1e-10);
    EXPECT_EQ(d.shift, t);
  }
  // Shifts wrap: -2 is 14 and 17 is 1 on a 16-cell.
  const AlignedDistance w = structure_distance(translate_field(b, {{-2, 5, 17}}), b);
  EXPECT_LT(w.distance, 1e-10);
  EXPECT_EQ(w.shift, (std::array<int, 3>{{14, 5, 1}}));
}

TEST(StructureDistance, IsSymmetricWithOppositeShifts) {
  const VoxelField a = smoothed_field(random_ids(12, 0.4, 2), 12), b = smoothed_field(random_ids(12, 0.4, 3), 12);
  const AlignedDistance ab = structure_distance(a, b), ba = structure_distance(b, a);
  EXPECT_GT(ab.distance, 0.05);
  EXPECT_NEAR(ab.distance, ba.distance, 1e-12);
  for (int axis = 0; axis < 3; ++axis) EXPECT_EQ((ab.shift[axis] + ba.shift[axis]) % 12, 0);
}

TEST(StructureDistance, FftMinimumEqualsBruteForceOverAllTranslations) {
  // 8: the radix-4 real transform; 6 and 7: the generic even and odd paths.
  for (int n : {8, 6, 7}) {
    const VoxelField a = embedding_random_field(n, 10 + n), b = embedding_random_field(n, 20 + n);
    std::array<int, 3> argmin{};
    const double brute = brute_force_distance(a, b, &argmin);
    const AlignedDistance d = structure_distance(a, b);
    EXPECT_NEAR(d.distance, brute, 1e-10) << "n = " << n;
    EXPECT_EQ(d.shift, argmin) << "n = " << n;
    // The same through the smoothed voxel structures the pipeline compares.
    const VoxelField sa = smoothed_field(random_ids(n, 0.5, n), n), sb = smoothed_field(random_ids(n, 0.5, 99 + n), n);
    EXPECT_NEAR(structure_distance(sa, sb).distance, brute_force_distance(sa, sb, &argmin), 1e-10) << "n = " << n;
  }
}

TEST(StructureDistance, BlurKeepsMassAndCommutesWithTranslation) {
  const VoxelField f = embedding_random_field(12, 5);
  for (double sigma : {0.7, 1.0, 4.0}) {  // 4.0: the kernel wraps around the cell more than once
    const VoxelField g = periodic_gaussian_blur(f, sigma);
    EXPECT_NEAR(g.values.sum(), f.values.sum(), 1e-10 * f.values.sum()) << sigma;
    EXPECT_LT(g.values.maxCoeff() - g.values.minCoeff(), f.values.maxCoeff() - f.values.minCoeff());
    const std::array<int, 3> t{{5, 11, 2}};
    const VoxelField a = periodic_gaussian_blur(translate_field(f, t), sigma), b = translate_field(g, t);
    EXPECT_LT((a.values - b.values).cwiseAbs().maxCoeff(), 1e-13) << sigma;
  }
  // A voxel in the corner spreads across the periodic boundary symmetrically.
  VoxelField spike(10);
  spike.at(0, 0, 0) = 1.0;
  const VoxelField s = periodic_gaussian_blur(spike, 1.0);
  EXPECT_NEAR(s.values.sum(), 1.0, 1e-14);
  EXPECT_DOUBLE_EQ(s.at(1, 0, 0), s.at(9, 0, 0));
  EXPECT_DOUBLE_EQ(s.at(0, 2, 0), s.at(0, 8, 0));
  EXPECT_DOUBLE_EQ(s.at(1, 0, 0), s.at(0, 0, 9));
  EXPECT_NEAR(s.at(1, 0, 0) / s.at(0, 0, 0), std::exp(-0.5), 1e-12);  // separable Gaussian, sigma 1
  EXPECT_EQ(periodic_gaussian_blur(f, 0.0).values, f.values);
  EXPECT_THROW(periodic_gaussian_blur(f, -1.0), InputError);
}

TEST(StructureDistance, BlurMakesOneVoxelDifferencesSmall) {
  // A thin plate one voxel thicker: the raw indicators differ by a whole
  // layer (1/16 of the voxels), the blurred fields by much less.
  const int n = 16;
  auto plate = [&](int thickness) {
    std::vector<int> ids(std::size_t(n) * n * n, 0);
    for (int k = 0; k < thickness; ++k)
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) ids[std::size_t(i) + n * (j + std::size_t(n) * k)] = 1;
    return ids;
  };
  const double raw =
      structure_distance(smoothed_field(plate(3), n, {1, 0.0}), smoothed_field(plate(4), n, {1, 0.0})).distance;
  const double smooth = structure_distance(smoothed_field(plate(3), n), smoothed_field(plate(4), n)).distance;
  EXPECT_NEAR(raw, 0.25, 1e-12);  // sqrt(1/16)
  EXPECT_LT(smooth, 0.6 * raw);
}

TEST(StructureDistance, PoolingAveragesBlocks) {
  const VoxelField f = embedding_random_field(8, 7);
  const VoxelField p = average_pool(f, 2);
  ASSERT_EQ(p.n, 4);
  EXPECT_NEAR(p.values.sum() * 8, f.values.sum(), 1e-12);
  double block = 0;
  for (int k = 2; k < 4; ++k)
    for (int j = 4; j < 6; ++j)
      for (int i = 6; i < 8; ++i) block += f.at(i, j, k);
  EXPECT_NEAR(p.at(3, 2, 1), block / 8, 1e-15);
  EXPECT_EQ(smoothed_field(random_ids(8, 0.5, 1), 8, {4, 1.0}).n, 2);
  EXPECT_THROW(average_pool(f, 3), InputError);
  EXPECT_THROW(structure_distance(f, p), InputError);
  EXPECT_THROW(solid_indicator(std::vector<int>(10, 1), 2), InputError);
}

TEST(StructureDistance, PairwiseMatrixMatchesPairsAndIgnoresThreadCount) {
  std::vector<VoxelField> fields;
  for (int s = 0; s < 7; ++s) fields.push_back(smoothed_field(random_ids(10, 0.2 + 0.05 * s, 40 + s), 10));
  fields.push_back(translate_field(fields[2], {{1, 2, 3}}));
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const MatX one = pairwise_structure_distances(fields);
  omp_set_num_threads(2);
  const MatX two = pairwise_structure_distances(fields);
  omp_set_num_threads(saved);
  EXPECT_EQ(one, two);
  EXPECT_EQ(one, one.transpose());
  EXPECT_EQ(one.diagonal().norm(), 0.0);
  EXPECT_LT(one(2, 7), 1e-10);
  for (int i = 0; i < 8; ++i)
    for (int j = i + 1; j < 8; ++j) EXPECT_NEAR(one(i, j), structure_distance(fields[i], fields[j]).distance, 1e-12);
  EXPECT_GT(one(0, 6), 0.1);
}

// ------------------------------------------------------------------ isomap

TEST(Isomap, ClassicalMdsRecoversEuclideanDistances) {
  std::mt19937_64 rng(3);
  MatX X(40, 3);
  for (Eigen::Index i = 0; i < X.size(); ++i) X.data()[i] = 2.0 * gaussian(rng);
  const MatX D = euclidean_distances(X);
  const MdsResult mds = classical_mds(D, 3);
  EXPECT_LT((euclidean_distances(mds.coordinates) - D).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_GT(mds.eigenvalues[2], 1.0);
  EXPECT_GE(mds.eigenvalues[0], mds.eigenvalues[1]);
  EXPECT_GE(mds.eigenvalues[1], mds.eigenvalues[2]);
  for (int a = 0; a < 3; ++a) {  // sign convention: the largest-magnitude entry is positive
    Eigen::Index big;
    mds.coordinates.col(a).cwiseAbs().maxCoeff(&big);
    EXPECT_GT(mds.coordinates(big, a), 0.0);
  }
  EXPECT_LT(residual_variance(D, mds.coordinates), 1e-12);
  // A complete neighbour graph keeps Euclidean distances as geodesics.
  const IsomapResult iso = isomap(D, {39, 3, true});
  EXPECT_LT((iso.geodesic - D).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((euclidean_distances(iso.coordinates) - D).cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT(iso.residual_variance, 1e-12);
  EXPECT_EQ(iso.kept.size(), 40u);
  EXPECT_TRUE(iso.left_out.empty());
  // Two dimensions cannot hold a 3-D cloud.
  EXPECT_GT(residual_variance(D, classical_mds(D, 2).coordinates), 1e-3);
}

TEST(Isomap, UnrollsASpiralThatPlainMdsCannot) {
  const int n = 100;
  MatX X(n, 3);
  for (int i = 0; i < n; ++i) {
    const double t = kEmbeddingPi + 3.0 * kEmbeddingPi * i / (n - 1);  // 1.5 turns, radius pi..4 pi
    X.row(i) << t * std::cos(t), t * std::sin(t), 0.05 * t;
  }
  const MatX D = euclidean_distances(X);
  const IsomapResult iso = isomap(D, {4, 2, true});
  ASSERT_EQ(iso.coordinates.rows(), n);
  int up = 0, down = 0;
  for (int i = 1; i < n; ++i) (iso.coordinates(i, 0) > iso.coordinates(i - 1, 0) ? up : down) += 1;
  EXPECT_TRUE(up == n - 1 || down == n - 1) << up << " up, " << down << " down";
  EXPECT_GT(iso.eigenvalues[0], 100 * iso.eigenvalues[1]);
  EXPECT_LT(iso.residual_variance, 1e-6);
  // Euclidean MDS folds the spiral: its first axis is not monotone.
  const MdsResult flat = classical_mds(D, 2);
  up = down = 0;
  for (int i = 1; i < n; ++i) (flat.coordinates(i, 0) > flat.coordinates(i - 1, 0) ? up : down) += 1;
  EXPECT_TRUE(up > 5 && down > 5);
}

TEST(Isomap, BeamThicknessFamilyEmbedsInOrder) {
  // Radius sweep of a cubic beam cross at 32^3, compared at 16^3. Radii
  // that voxelize like the previous one add nothing and are skipped.
  std::vector<VoxelField> fields;
  std::vector<int> last;
  for (double r = 2.0; r <= 7.0; r += 0.1) {
    std::vector<int> ids = beam_cross(32, r);
    if (ids == last) continue;
    fields.push_back(smoothed_field(ids, 32, {2, 1.0}));
    last = std::move(ids);
  }
  const int count = static_cast<int>(fields.size());
  ASSERT_GT(count, 15);
  const MatX D = pairwise_structure_distances(fields);
  for (int s = 1; s < count; ++s) ASSERT_GT(D(s - 1, s), 0.0);
  const IsomapResult iso = isomap(D, {3, 2, true});
  int up = 0, down = 0;
  for (int s = 1; s < count; ++s) (iso.coordinates(s, 0) > iso.coordinates(s - 1, 0) ? up : down) += 1;
  EXPECT_TRUE(up == count - 1 || down == count - 1) << up << " up, " << down << " down";
  EXPECT_LT(iso.residual_variance, 1e-3);
}

TEST(Isomap, DisconnectedGraphEmbedsTheLargestComponent) {
  std::mt19937_64 rng(11);
  MatX X(20, 3);
  for (int i = 0; i < 20; ++i)
    for (int a = 0; a < 3; ++a) X(i, a) = uniform(rng) + (i < 8 && a == 0 ? 100.0 : 0.0);
  const MatX D = euclidean_distances(X);
  const IsomapResult iso = isomap(D, {3, 2, false});
  EXPECT_EQ(iso.components, 2);
  std::vector<int> small(8), large(12);
  for (int i = 0; i < 8; ++i) small[i] = i;
  for (int i = 0; i < 12; ++i) large[i] = 8 + i;
  EXPECT_EQ(iso.left_out, small);
  EXPECT_EQ(iso.kept, large);
  EXPECT_EQ(iso.coordinates.rows(), 12);
  EXPECT_TRUE(iso.geodesic.allFinite());
  try {
    isomap(D, {3, 2, true});
    ADD_FAILURE() << "a disconnected graph was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2 components (sizes 8, 12)"), std::string::npos) << e.what();
  }
  const std::vector<int> comp = connected_components(knn_graph(D, 3));
  EXPECT_EQ(comp[0], 0);
  EXPECT_EQ(comp[19], 1);
  EXPECT_TRUE(std::isinf(geodesic_distances(knn_graph(D, 3))(0, 19)));
}

TEST(Isomap, JoinedComponentsEmbedEveryPointAndStayApart) {
  std::mt19937_64 rng(11);
  MatX X(30, 3);
  // Three groups of 10, far apart along x (0, 100, 300).
  for (int i = 0; i < 30; ++i)
    for (int a = 0; a < 3; ++a) X(i, a) = uniform(rng) + (a == 0 ? (i < 10 ? 0.0 : i < 20 ? 100.0 : 300.0) : 0.0);
  const MatX D = euclidean_distances(X);
  NeighborGraph graph = knn_graph(D, 3);
  const std::vector<int> separate = connected_components(graph);
  ASSERT_EQ(*std::max_element(separate.begin(), separate.end()), 2);
  EXPECT_EQ(connect_components(graph, D), 2);  // k components gain k - 1 edges
  const std::vector<int> joined = connected_components(graph);
  EXPECT_EQ(*std::max_element(joined.begin(), joined.end()), 0);
  IsomapOptions options{3, 2, false, true};
  const IsomapResult iso = isomap(D, options);
  EXPECT_EQ(iso.components, 3);
  EXPECT_TRUE(iso.left_out.empty());
  ASSERT_EQ(iso.coordinates.rows(), 30);
  // The groups keep their order and spacing on the first axis: the joins
  // are the shortest gaps (about 100 and 200).
  const auto mean = [&](int g) { return iso.coordinates.col(0).segment(10 * g, 10).mean(); };
  const double gap1 = std::abs(mean(1) - mean(0)), gap2 = std::abs(mean(2) - mean(1));
  EXPECT_NEAR(gap1, 100.0, 5.0);
  EXPECT_NEAR(gap2, 200.0, 5.0);
  for (int g = 0; g < 3; ++g)
    for (int i = 0; i < 10; ++i) EXPECT_LT(std::abs(iso.coordinates(10 * g + i, 0) - mean(g)), 5.0);
}

TEST(Isomap, RejectsBadInput) {
  MatX D = euclidean_distances(MatX::Random(6, 2));
  EXPECT_THROW(knn_graph(D, 6), InputError);
  EXPECT_THROW(knn_graph(D, 0), InputError);
  EXPECT_THROW(isomap(D, {2, 6, false}), InputError);  // 6 dimensions need 7 points
  MatX A = D;
  A(0, 1) += 0.5;
  EXPECT_THROW(isomap(A, {2, 2, false}), InputError);
  A = D;
  A(3, 3) = 1.0;
  EXPECT_THROW(knn_graph(A, 2), InputError);
  EXPECT_THROW(knn_graph(MatX::Zero(3, 4), 1), InputError);
}

// ---------------------------------------------------------------- mixtures

MatX blobs(const std::vector<Eigen::VectorXd>& centres, const std::vector<int>& counts, double sd,
           std::vector<int>* truth, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  int total = 0;
  for (int c : counts) total += c;
  const Eigen::Index d = centres[0].size();
  MatX X(total, d);
  int row = 0;
  for (std::size_t b = 0; b < centres.size(); ++b)
    for (int i = 0; i < counts[b]; ++i, ++row) {
      for (Eigen::Index a = 0; a < d; ++a) X(row, a) = centres[b][a] + sd * (a == 0 ? 2.0 : 1.0) * gaussian(rng);
      truth->push_back(int(b));
    }
  return X;
}

// Labels equal to the truth up to a renaming of the components.
bool same_partition(const std::vector<int>& labels, const std::vector<int>& truth) {
  std::map<int, int> forward, backward;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    auto f = forward.emplace(truth[i], labels[i]).first;
    auto b = backward.emplace(labels[i], truth[i]).first;
    if (f->second != labels[i] || b->second != truth[i]) return false;
  }
  return true;
}

TEST(GaussianMixture, BicFindsTwoAndThreeSeparatedBlobs) {
  std::vector<int> truth2;
  const MatX X2 = blobs({Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 12)}, {150, 100}, 1.0, &truth2, 1);
  const GmmSelection s2 = select_gaussian_mixture(X2, 1, 4, {});
  EXPECT_EQ(s2.best.weights.size(), 2);
  EXPECT_EQ(s2.components, (std::vector<int>{1, 2, 3, 4}));
  EXPECT_EQ(*std::min_element(s2.bic.begin(), s2.bic.end()), s2.bic[1]);
  EXPECT_TRUE(same_partition(s2.best.labels, truth2));
  std::vector<int> sizes = s2.best.sizes;
  std::sort(sizes.begin(), sizes.end());
  EXPECT_EQ(sizes, (std::vector<int>{100, 150}));

  std::vector<int> truth3;
  const MatX X3 = blobs({Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(15, 0, 0), Eigen::Vector3d(5, 10, 3)}, {120, 80, 60},
                        1.0, &truth3, 2);
  const GmmSelection s3 = select_gaussian_mixture(X3, 1, 5, {});
  EXPECT_EQ(s3.best.weights.size(), 3);
  EXPECT_TRUE(same_partition(s3.best.labels, truth3));
  EXPECT_TRUE(s3.best.converged);
  // The winner's BIC is the formula's.
  EXPECT_NEAR(s3.best.bic, -2 * s3.best.log_likelihood + 29 * std::log(260.0), 1e-9 * s3.best.bic);
  EXPECT_EQ(gmm_parameter_count(3, 3), 29);
  EXPECT_EQ(gmm_parameter_count(1, 2), 5);
}

TEST(GaussianMixture, LogLikelihoodNeverDecreases) {
  // Overlapping blobs and too many components: a long EM run.
  std::vector<int> truth;
  const MatX X =
      blobs({Eigen::Vector2d(0, 0), Eigen::Vector2d(2.5, 1), Eigen::Vector2d(-1, 3)}, {100, 100, 100}, 1.0, &truth, 5);
  GmmOptions o;
  o.components = 4;
  o.restarts = 3;
  const GaussianMixture g = fit_gaussian_mixture(X, o);
  const std::vector<double>& h = g.log_likelihood_history;
  ASSERT_GT(h.size(), 10u);
  for (std::size_t t = 1; t < h.size(); ++t) EXPECT_GE(h[t], h[t - 1] - 1e-12 * std::abs(h[t - 1])) << "step " << t;
  EXPECT_EQ(h.back(), g.log_likelihood);
  EXPECT_EQ(int(h.size()), g.iterations + 1);
  EXPECT_NEAR(g.weights.sum(), 1.0, 1e-12);
  EXPECT_LT((g.responsibilities.rowwise().sum().array() - 1.0).abs().maxCoeff(), 1e-12);
  // The model's own responsibilities are what it reports.
  double L = 0;
  const MatX R = gmm_responsibilities(g, X, &L);
  EXPECT_LT((R - g.responsibilities).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(L, g.log_likelihood, 1e-9 * std::abs(L));
}

TEST(GaussianMixture, SameSeedSameResultForAnyThreadCount) {
  std::vector<int> truth;
  const MatX X =
      blobs({Eigen::Vector2d(0, 0), Eigen::Vector2d(4, 0), Eigen::Vector2d(0, 5)}, {80, 70, 60}, 1.0, &truth, 9);
  GmmOptions o;
  o.components = 3;
  o.restarts = 5;
  o.seed = 1234;
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const GaussianMixture a = fit_gaussian_mixture(X, o), b = fit_gaussian_mixture(X, o);
  omp_set_num_threads(2);
  const GaussianMixture c = fit_gaussian_mixture(X, o);
  omp_set_num_threads(saved);
  for (const GaussianMixture* g : {&b, &c}) {
    EXPECT_EQ(g->means, a.means);
    EXPECT_EQ(g->weights, a.weights);
    EXPECT_EQ(g->log_likelihood_history, a.log_likelihood_history);
    EXPECT_EQ(g->labels, a.labels);
    EXPECT_EQ(g->restart, a.restart);
  }
}

TEST(GaussianMixture, RejectsBadInput) {
  GmmOptions o;
  o.components = 5;
  EXPECT_THROW(fit_gaussian_mixture(MatX::Random(4, 2), o), InputError);
  o.components = 2;
  EXPECT_THROW(fit_gaussian_mixture(MatX::Ones(10, 2), o), InputError);
  o.restarts = 0;
  EXPECT_THROW(fit_gaussian_mixture(MatX::Random(10, 2), o), InputError);
  EXPECT_THROW(select_gaussian_mixture(MatX::Random(10, 2), 3, 2, {}), InputError);
}

}  // namespace
}  // namespace msfab
