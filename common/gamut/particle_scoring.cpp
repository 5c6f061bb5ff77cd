#include "gamut/particle_scoring.hpp"

#include <cmath>
#include <numeric>

#include "core/errors.hpp"

namespace msfab {

double sample_density(const VecX& p, const std::vector<VecX>& samples, double h) {
  if (!(h > 0)) throw InputError("sample density: support radius must be > 0");
  double D = 0;
  for (const VecX& q : samples) {
    const double s = (p - q).squaredNorm() / (h * h);
    if (s < 1) D += std::pow(1 - s, 4);
  }
  return D;
}

double particle_score(double phi, double density, double depth) {
  if (!(depth > 0)) throw InputError("particle score: depth must be > 0");
  if (!(density > 0)) return 0.0;
  return std::max(0.0, 1.0 - std::abs(phi) / depth) / (density * density);
}

std::vector<int> systematic_resample(const std::vector<double>& weights, int count, double u0) {
  if (weights.empty() || count < 0) throw InputError("resampling: no weights or a negative count");
  if (!(u0 >= 0 && u0 < 1)) throw InputError("resampling: the offset must be in [0, 1)");
  double total = 0;
  for (double w : weights) {
    if (!(w >= 0) || !std::isfinite(w)) throw InputError("resampling: weights must be finite and >= 0");
    total += w;
  }
  if (!(total > 0)) throw InputError("resampling: all weights are zero");
  std::vector<int> out;
  out.reserve(count);
  double cumulative = weights[0] / total;
  int i = 0;
  for (int m = 0; m < count; ++m) {
    const double u = (m + u0) / count;
    while (u >= cumulative && i + 1 < static_cast<int>(weights.size())) cumulative += weights[++i] / total;
    out.push_back(i);
  }
  return out;
}

}  // namespace msfab
