#include "ddfem/db_compression.hpp"

#include <cmath>
#include <limits>
#include <random>
#include <sstream>

#include "core/errors.hpp"

namespace msfab {
double uniform_pm1(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-52 - 1.0; }

std::vector<Vec24> common_deformations(const hex8::NodeMatrix& coarse_rest, int count, double strain,
                                       std::uint64_t seed) {
  if (count < 1) throw InputError("compression: the number of common deformations must be >= 1");
  if (!(strain > 0 && strain < 0.5)) throw InputError("compression: deformation strain must be in (0, 0.5)");
  std::mt19937_64 rng(seed);
  const Vec3 center = coarse_rest.colwise().mean().transpose();
  const double edge = (coarse_rest.row(7) - coarse_rest.row(0)).maxCoeff();
  std::vector<Vec24> out;
  for (int s = 0; s < count; ++s) {
    Mat3 G;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) G(i, j) = uniform_pm1(rng);
    G = 0.5 * (G + G.transpose());
    G *= strain / G.norm();
    Vec24 u;
    for (int c = 0; c < 8; ++c) {
      const Vec3 r = coarse_rest.row(c).transpose() - center;
      Vec3 extra(uniform_pm1(rng), uniform_pm1(rng), uniform_pm1(rng));
      u.segment<3>(3 * c) = G * r + (strain / 3.0) * 0.5 * edge * extra;
    }
    out.push_back(u);
  }
  return out;
}

std::vector<Vec24> corner_deformations(const hex8::NodeMatrix& coarse_rest, double strain) {
  if (!(strain > 0 && strain < 0.5)) throw InputError("compression: deformation strain must be in (0, 0.5)");
  const double edge = (coarse_rest.row(7) - coarse_rest.row(0)).maxCoeff();
  std::vector<Vec24> out;
  for (int c = 0; c < 8; ++c)
    for (int a = 0; a < 3; ++a) {
      Vec24 u = Vec24::Zero();
      u[3 * c + a] = strain * edge;
      out.push_back(u);
    }
  return out;
}

MatX energy_features(const std::vector<CoarseMaterialFit>& entries, const std::vector<Vec24>& deformations,
                     double voxel_size) {
  std::vector<MaterialPtr> one{nullptr};
  FineBlock unit;
  unit.voxel_size = voxel_size;
  const hex8::NodeMatrix X = unit.coarse_rest_positions();
  // Each fit on the element it was fitted for.
  const hex8::ElementGeometry trilinear = coarse_fit_geometry(X, 8, false), enhanced = coarse_fit_geometry(X, 8, true);
  MatX features(entries.size(), deformations.size());
  for (std::size_t e = 0; e < entries.size(); ++e)
    for (std::size_t s = 0; s < deformations.size(); ++s) {
      const double V = coarse_energy(entries[e], entries[e].enhanced ? enhanced : trilinear, X, deformations[s]);
      if (!(V > 0) || !std::isfinite(V)) {
        std::ostringstream os;
        os << "compression: coarse material " << e << " has energy " << V << " at common deformation " << s
           << " (must be positive and finite)";
        throw InputError(os.str());
      }
      features(e, s) = std::log(V);
    }
  return features;
}

bool is_homogeneous(const BlockMaterials& ids) {
  for (int c = 1; c < 8; ++c)
    if (ids[c] != ids[0]) return false;
  return ids[0] > 0;
}

FarthestPointSet farthest_point_sampling(const MatX& features, int k, const std::vector<int>& seeds) {
  const int n = static_cast<int>(features.rows());
  if (k < 1 || k > n) throw InputError("compression: representatives must be in [1, " + std::to_string(n) + "]");
  if (seeds.empty()) throw std::invalid_argument("farthest_point_sampling: no seed");
  for (int row : seeds)
    if (row < 0 || row >= n) throw std::invalid_argument("farthest_point_sampling: seed out of range");
  FarthestPointSet out;
  out.nearest.assign(n, 0);
  out.distance.assign(n, std::numeric_limits<double>::infinity());
  auto add = [&](int row) {
    const int index = static_cast<int>(out.representatives.size());
    out.representatives.push_back(row);
    // Each row is updated on its own, so threads cannot change the result.
#pragma omp parallel for schedule(static)
    for (int i = 0; i < n; ++i) {
      const double d = (features.row(i) - features.row(row)).norm();
      if (d < out.distance[i]) out.distance[i] = d, out.nearest[i] = index;  // strict: earlier wins ties
    }
  };
  for (int row : seeds)
    if (static_cast<int>(out.representatives.size()) < k && out.distance[row] > 0) add(row);
  while (static_cast<int>(out.representatives.size()) < k) {
    int far = 0;
    for (int i = 1; i < n; ++i)
      if (out.distance[i] > out.distance[far]) far = i;
    add(far);
  }
  return out;
}

CoarseDatabase compress_database(const CoarseDatabase& full, int k, int deformations, double strain, std::uint64_t seed,
                                 CompressionReport* report, bool corner_moves) {
  if (full.compressed()) throw InputError("compression: the input database is already compressed");
  FineBlock unit;
  unit.voxel_size = 1e-3;
  auto defs = common_deformations(unit.coarse_rest_positions(), deformations, strain, seed);
  if (corner_moves)
    for (const Vec24& u : corner_deformations(unit.coarse_rest_positions(), strain)) defs.push_back(u);
  // Only fitted entries take part (a database with void children keeps the
  // blocks it could not fit, and the all-void one, as unfitted rows; online
  // they are coarsened naively, so they map to no representative).
  std::vector<CoarseMaterialFit> fitted;
  std::vector<int> row_of_entry(full.entries.size(), -1);
  for (std::size_t e = 0; e < full.entries.size(); ++e)
    if (full.entries[e].fitted) {
      row_of_entry[e] = static_cast<int>(fitted.size());
      fitted.push_back(full.entries[e]);
    }
  if (fitted.empty()) throw InputError("compression: the database has no fitted coarse material");
  const MatX features = energy_features(fitted, defs, unit.voxel_size);
  std::vector<int> seeds;
  for (std::size_t e = 0; e < fitted.size(); ++e)
    if (is_homogeneous(fitted[e].material_ids)) seeds.push_back(static_cast<int>(e));
  if (seeds.empty()) seeds.push_back(0);
  const FarthestPointSet fps = farthest_point_sampling(features, k, seeds);

  CoarseDatabase out = full;
  out.entries.clear();
  for (int row : fps.representatives) out.entries.push_back(fitted[row]);
  for (auto& e : out.entry_of)
    if (e >= 0) e = row_of_entry[e] >= 0 ? fps.nearest[row_of_entry[e]] : -1;
  if (report) {
    *report = CompressionReport();
    double n = 0, err = 0;
    for (std::size_t i = 0; i < fps.distance.size(); ++i) {
      report->mean_distance += fps.distance[i];
      report->max_distance = std::max(report->max_distance, fps.distance[i]);
      const int rep = fps.representatives[fps.nearest[i]];
      for (int s = 0; s < features.cols(); ++s, ++n) err += std::abs(std::exp(features(rep, s) - features(i, s)) - 1);
    }
    report->mean_distance /= fps.distance.size();
    report->mean_energy_error = err / n;
  }
  return out;
}

}  // namespace msfab
