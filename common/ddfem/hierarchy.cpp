#include "ddfem/hierarchy.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "core/errors.hpp"
#include "ddfem/db_compression.hpp"
#include "ddfem/fine_block.hpp"

namespace msfab {
namespace {

// Child-index step of one cell along the stage's axis (x, y, z).
constexpr std::array<int, 3> kAxisOffset{4, 2, 1};

}  // namespace

Vec3 SmoothDeformation::at(const Vec3& x) const {
  const Vec3 y = x / length;
  Eigen::Matrix<double, 6, 1> q;
  q << y.x() * y.x(), y.y() * y.y(), y.z() * y.z(), y.x() * y.y(), y.y() * y.z(), y.x() * y.z();
  return length * strain * (A * y + B * q);
}

std::vector<SmoothDeformation> smooth_deformations(double length, int count, double strain, std::uint64_t seed) {
  if (count < 1) throw InputError("level 2: the number of common deformations must be >= 1");
  if (!(strain > 0 && strain < 0.5)) throw InputError("level 2: deformation strain must be in (0, 0.5)");
  if (!(length > 0)) throw InputError("level 2: cell size must be > 0");
  std::mt19937_64 rng(seed);
  std::vector<SmoothDeformation> out(count);
  for (SmoothDeformation& d : out) {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) d.A(i, j) = uniform_pm1(rng);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 6; ++j) d.B(i, j) = uniform_pm1(rng);
    d.A /= d.A.norm();
    d.B /= d.B.norm();
    d.length = length;
    d.strain = strain;
  }
  return out;
}

std::vector<Mat24> level1_rest_stiffness(const std::vector<CoarseMaterialFit>& level1, double child_size) {
  FineBlock element;  // geometry of one level-1 element (edge 2 voxels = child_size)
  element.voxel_size = 0.5 * child_size;
  const hex8::NodeMatrix X = element.coarse_rest_positions();
  const hex8::ElementGeometry trilinear = coarse_fit_geometry(X, 8, false), enhanced = coarse_fit_geometry(X, 8, true);
  std::vector<Mat24> K(level1.size());
  for (std::size_t e = 0; e < level1.size(); ++e) {
    const QuadratureMaterials m = coarse_quadrature_materials(level1[e]);
    const hex8::ElementGeometry& geo = level1[e].enhanced ? enhanced : trilinear;
    hex_evaluate(coarse_element_geometry(geo, X, m), m, X, nullptr, &K[e]);
    if (!K[e].allFinite())
      throw InputError("level 2: level-1 coarse material " + std::to_string(e) + " has a non-finite stiffness");
  }
  return K;
}

Mat24 condensed_stiffness(const Arrangement& arr, const std::vector<Mat24>& K1, Eigen::Vector3i* extent) {
  // Lattice nodes (i, j, k), i, j, k in 0..2, used by the arrangement.
  auto lattice = [](int c, int n) {  // node n of child c
    return Eigen::Vector3i((c >> 2 & 1) + (n >> 2 & 1), (c >> 1 & 1) + (n >> 1 & 1), (c & 1) + (n & 1));
  };
  Eigen::Vector3i hi(0, 0, 0);
  for (int c = 0; c < 8; ++c)
    if (arr[c] >= 0) hi = hi.cwiseMax(lattice(c, 7));
  if (extent) *extent = hi;
  // Number the nodes: the 8 box corners first (hex8 order), then the rest.
  std::array<int, 27> dof_node;
  dof_node.fill(-1);
  auto key = [](const Eigen::Vector3i& p) { return p.x() * 9 + p.y() * 3 + p.z(); };
  for (int n = 0; n < 8; ++n)
    dof_node[key(Eigen::Vector3i((n >> 2 & 1) * hi.x(), (n >> 1 & 1) * hi.y(), (n & 1) * hi.z()))] = n;
  int nodes = 8;
  for (int c = 0; c < 8; ++c)
    if (arr[c] >= 0)
      for (int n = 0; n < 8; ++n)
        if (dof_node[key(lattice(c, n))] < 0) dof_node[key(lattice(c, n))] = nodes++;
  MatX K = MatX::Zero(3 * nodes, 3 * nodes);
  for (int c = 0; c < 8; ++c) {
    if (arr[c] < 0) continue;
    const Mat24& Ke = K1.at(arr[c]);
    for (int a = 0; a < 8; ++a)
      for (int b = 0; b < 8; ++b)
        K.block<3, 3>(3 * dof_node[key(lattice(c, a))], 3 * dof_node[key(lattice(c, b))]) +=
            Ke.block<3, 3>(3 * a, 3 * b);
  }
  const int ni = 3 * (nodes - 8);
  if (ni == 0) return K.topLeftCorner<24, 24>();
  // A relative shift keeps K_ii invertible where a level-1 material has a
  // zero-energy mode; it is far below any physical stiffness.
  MatX Kii = K.bottomRightCorner(ni, ni);
  const double diag = Kii.diagonal().cwiseAbs().maxCoeff();
  if (!(diag > 0.0)) return K.topLeftCorner<24, 24>();  // all void inside: nothing to condense
  Kii.diagonal().array() += 1e-12 * diag;
  const Eigen::LDLT<MatX> ldlt(Kii);
  const MatX Kic = K.bottomLeftCorner(ni, 24);
  return K.topLeftCorner<24, 24>() - Kic.transpose() * ldlt.solve(Kic);
}

Vec24 box_corner_displacements(const SmoothDeformation& d, const Eigen::Vector3i& extent, double child_size) {
  Vec24 u;
  for (int n = 0; n < 8; ++n)
    u.segment<3>(3 * n) =
        d.at(child_size * Vec3((n >> 2 & 1) * extent.x(), (n >> 1 & 1) * extent.y(), (n & 1) * extent.z()));
  return u;
}

int Level2Hierarchy::lookup(const Arrangement& e) const {
  auto pair = [](const PairStage& s, int a, int b) {
    if (a < 0 || b < 0 || a >= s.inputs || b >= s.inputs)
      throw std::out_of_range("Level2Hierarchy::lookup: entry outside the stage's alphabet");
    return s.table[static_cast<std::size_t>(a) * s.inputs + b];
  };
  // Along x: children (0, j, k) and (1, j, k); then y; then z.
  std::array<int, 4> x;
  for (int jk = 0; jk < 4; ++jk) x[jk] = pair(stages[0], e[jk], e[4 + jk]);
  const std::array<int, 2> y{pair(stages[1], x[0], x[2]), pair(stages[1], x[1], x[3])};
  return pair(stages[2], y[0], y[1]);
}

Arrangement Level2Hierarchy::arrangement(int stage, int r) const {
  Arrangement out;
  out.fill(-1);
  if (stage < 0) {
    out[0] = r;
    return out;
  }
  const auto [a, b] = stages.at(stage).pairs.at(r);
  const Arrangement low = arrangement(stage - 1, a), high = arrangement(stage - 1, b);
  for (int c = 0; c < 8; ++c)
    if (low[c] >= 0) out[c] = low[c], out[c + kAxisOffset[stage]] = high[c];
  return out;
}

Level2Hierarchy build_level2_hierarchy(const std::vector<CoarseMaterialFit>& level1, double child_size,
                                       const HierarchyOptions& options, bool void_input) {
  if (level1.empty()) throw InputError("level 2: the level-1 database has no coarse materials");
  for (std::size_t e = 0; e < level1.size(); ++e)
    if (!level1[e].fitted || level1[e].points() != 8)
      throw InputError("level 2: level-1 coarse material " + std::to_string(e) + " is not a fitted 8-point material");
  for (int k : options.representatives)
    if (k < 1) throw InputError("level 2: representatives per stage must be >= 1");
  const auto defs = smooth_deformations(2 * child_size, options.deformations, options.strain, options.seed);
  std::vector<Mat24> K1 = level1_rest_stiffness(level1, child_size);
  if (void_input) K1.push_back(Mat24::Zero());  // the all-void child
  const int D = static_cast<int>(defs.size());

  Level2Hierarchy h;
  h.void_input = void_input;
  int inputs = static_cast<int>(K1.size());
  // Seeds (kept exactly, docs/ddfem.md): the homogeneous level-1 materials;
  // then at each stage every seed paired with itself and every two uniform
  // items paired with each other: all cells of one material, and all
  // layerings of uniform level-1 elements along one axis.
  std::vector<int> seeds, uniform;
  for (int e = 0; e < static_cast<int>(level1.size()); ++e)
    if (is_homogeneous(level1[e].material_ids)) seeds.push_back(e), uniform.push_back(e);
  if (void_input) seeds.push_back(inputs - 1), uniform.push_back(inputs - 1);
  for (int s = 0; s < 3; ++s) {
    std::vector<Arrangement> items(inputs);
    for (int t = 0; t < inputs; ++t) items[t] = h.arrangement(s - 1, t);
    const std::int64_t candidates = static_cast<std::int64_t>(inputs) * inputs;
    // Every candidate of a stage spans the same box, so the corner
    // displacements are shared.
    Arrangement probe = items[0];
    for (int c = 0; c < 8; ++c)
      if (items[0][c] >= 0) probe[c + kAxisOffset[s]] = items[0][c];
    Eigen::Vector3i extent;
    condensed_stiffness(probe, K1, &extent);
    Eigen::Matrix<double, 24, Eigen::Dynamic> U(24, D);
    for (int d = 0; d < D; ++d) U.col(d) = box_corner_displacements(defs[d], extent, child_size);
    MatX features(candidates, options.features());
#pragma omp parallel for schedule(static)
    for (std::int64_t ab = 0; ab < candidates; ++ab) {
      Arrangement arr = items[ab / inputs];
      const Arrangement& high = items[ab % inputs];
      for (int c = 0; c < 8; ++c)
        if (high[c] >= 0) arr[c + kAxisOffset[s]] = high[c];
      const Mat24 S = condensed_stiffness(arr, K1);
      const VecX energy = 0.5 * (U.transpose() * S * U).diagonal();
      // A floor keeps log finite for a mode the candidate does not resist.
      for (int d = 0; d < D; ++d) features(ab, d) = std::log(std::max(energy[d], 1e-300));
      // A corner moved alone by u stores S_ii u^2 / 2; the constant factor
      // drops out of the distances.
      if (options.corner_moves)
        for (int i = 0; i < 24; ++i) features(ab, D + i) = std::log(std::max(S(i, i), 1e-300));
    }

    PairStage& stage = h.stages[s];
    stage.inputs = inputs;
    const int k = static_cast<int>(std::min<std::int64_t>(options.representatives[s], candidates));
    std::vector<int> rows;
    for (int a : seeds) rows.push_back(a * inputs + a);
    for (int a : uniform)
      for (int b : uniform)
        if (a != b) rows.push_back(a * inputs + b);
    if (rows.empty()) {  // no homogeneous material: a seeded random start
      std::mt19937_64 rng(options.seed + 0x9e3779b97f4a7c15ULL * (s + 1));
      rows.push_back(static_cast<int>(rng() % candidates));
    }
    const FarthestPointSet fps = farthest_point_sampling(features, k, rows);
    stage.table = fps.nearest;
    for (int row : fps.representatives) stage.pairs.push_back({row / inputs, row % inputs});
    // The seeds that made it in, and which of them are one material.
    const std::vector<int> kept_uniform = uniform;
    seeds.clear();
    uniform.clear();
    for (int p = 0; p < k && p < static_cast<int>(rows.size()); ++p) {
      const int row = fps.representatives[p];
      if (std::find(rows.begin(), rows.end(), row) == rows.end()) break;  // past the seeds
      seeds.push_back(p);
      const int a = row / inputs, b = row % inputs;
      if (a == b && std::find(kept_uniform.begin(), kept_uniform.end(), a) != kept_uniform.end()) uniform.push_back(p);
    }
    for (double d : fps.distance) {
      stage.mean_distance += d / candidates;
      stage.max_distance = std::max(stage.max_distance, d);
    }
    inputs = k;
  }
  return h;
}

}  // namespace msfab
