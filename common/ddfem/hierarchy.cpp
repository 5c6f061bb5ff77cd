#include "ddfem/hierarchy.hpp"

#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

#include "core/errors.hpp"
#include "ddfem/db_compression.hpp"
#include "ddfem/fine_block.hpp"

namespace msfab {
namespace {

// Child-index step of one cell along the stage's axis (x, y, z).
constexpr std::array<int, 3> kAxisOffset{4, 2, 1};

double uniform_pm1(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-52 - 1.0; }

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

std::vector<std::array<std::vector<double>, 8>> child_energies(const std::vector<CoarseMaterialFit>& level1,
                                                               double child_size,
                                                               const std::vector<SmoothDeformation>& defs) {
  FineBlock element;  // geometry of one level-1 element (edge 2 voxels = child_size)
  element.voxel_size = 0.5 * child_size;
  const hex8::ElementGeometry geo = element.coarse_geometry();
  const hex8::NodeMatrix X = element.coarse_rest_positions();
  const int n = static_cast<int>(level1.size());
  std::vector<std::array<std::vector<double>, 8>> out(n);
  // Corner displacements of child c under deformation d, shared by all entries.
  std::vector<std::array<Vec24, 8>> u(defs.size());
  for (std::size_t d = 0; d < defs.size(); ++d)
    for (int c = 0; c < 8; ++c) {
      const Vec3 origin = child_size * Vec3(c >> 2 & 1, c >> 1 & 1, c & 1);
      for (int a = 0; a < 8; ++a) u[d][c].segment<3>(3 * a) = defs[d].at(origin + X.row(a).transpose());
    }
  std::string failure;
#pragma omp parallel for schedule(dynamic, 4)
  for (int e = 0; e < n; ++e)
    for (int c = 0; c < 8; ++c) {
      out[e][c].resize(defs.size());
      for (std::size_t d = 0; d < defs.size(); ++d) {
        const double V = coarse_energy(level1[e], geo, X, u[d][c]);
        out[e][c][d] = V;
        if (!(V > 0) || !std::isfinite(V)) {
          std::ostringstream os;
          os << "level 2: level-1 coarse material " << e << " has energy " << V << " at common deformation " << d
             << " (must be positive and finite)";
#pragma omp critical(msfab_child_energy_failure)
          if (failure.empty()) failure = os.str();
        }
      }
    }
  if (!failure.empty()) throw InputError(failure);
  return out;
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
                                       const HierarchyOptions& options) {
  if (level1.empty()) throw InputError("level 2: the level-1 database has no coarse materials");
  for (std::size_t e = 0; e < level1.size(); ++e)
    if (!level1[e].fitted || level1[e].points() != 8)
      throw InputError("level 2: level-1 coarse material " + std::to_string(e) + " is not a fitted 8-point material");
  for (int k : options.representatives)
    if (k < 1) throw InputError("level 2: representatives per stage must be >= 1");
  const auto defs = smooth_deformations(2 * child_size, options.deformations, options.strain, options.seed);
  const auto E1 = child_energies(level1, child_size, defs);
  const int D = static_cast<int>(defs.size());

  Level2Hierarchy h;
  int inputs = static_cast<int>(level1.size());
  for (int s = 0; s < 3; ++s) {
    // Energy of each input item at its own place and shifted one cell along the axis.
    std::vector<std::array<std::vector<double>, 2>> item(inputs);
    for (int t = 0; t < inputs; ++t) {
      const Arrangement arr = h.arrangement(s - 1, t);
      for (int shift = 0; shift < 2; ++shift) {
        item[t][shift].assign(D, 0.0);
        for (int c = 0; c < 8; ++c)
          if (arr[c] >= 0)
            for (int d = 0; d < D; ++d) item[t][shift][d] += E1[arr[c]][c + shift * kAxisOffset[s]][d];
      }
    }
    const std::int64_t candidates = static_cast<std::int64_t>(inputs) * inputs;
    MatX features(candidates, D);
#pragma omp parallel for schedule(static)
    for (std::int64_t ab = 0; ab < candidates; ++ab)
      for (int d = 0; d < D; ++d) features(ab, d) = std::log(item[ab / inputs][0][d] + item[ab % inputs][1][d]);

    PairStage& stage = h.stages[s];
    stage.inputs = inputs;
    const int k = static_cast<int>(std::min<std::int64_t>(options.representatives[s], candidates));
    std::mt19937_64 rng(options.seed + 0x9e3779b97f4a7c15ULL * (s + 1));
    const FarthestPointSet fps = farthest_point_sampling(features, k, static_cast<int>(rng() % candidates));
    stage.table = fps.nearest;
    for (int row : fps.representatives) stage.pairs.push_back({row / inputs, row % inputs});
    for (double d : fps.distance) {
      stage.mean_distance += d / candidates;
      stage.max_distance = std::max(stage.max_distance, d);
    }
    inputs = k;
  }
  return h;
}

}  // namespace msfab
