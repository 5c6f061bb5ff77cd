#include "dynamics/harmonic_inversion.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <string>

#include "core/errors.hpp"

namespace msfab {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kMinSamples = 16;

// Pole of the least-squares model: a conjugate pair contributes the two
// columns r^k cos(w k), r^k sin(w k); a real pole the single column z^k.
struct Pole {
  double log_r = 0.0;  // log |z|
  double omega = 0.0;  // arg z in [0, pi]
  bool real = false;
};

std::string field(const char* name, double value) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", value);
  return std::string("harmonic_inversion: ") + name + " = " + buf;
}

void validate(const VecX& y, double dt, const HarmonicInversionOptions& opt) {
  if (!(dt > 0.0) || !std::isfinite(dt))
    throw InputError(field("sample_interval", dt) + ": must be positive and finite");
  if (y.size() < kMinSamples)
    throw InputError("harmonic_inversion: " + std::to_string(y.size()) + " samples: need at least " +
                     std::to_string(kMinSamples));
  for (Eigen::Index k = 0; k < y.size(); ++k)
    if (!std::isfinite(y[k])) throw InputError("harmonic_inversion: sample " + std::to_string(k) + " is not finite");
  if (opt.num_modes < 0) throw InputError(field("num_modes", opt.num_modes) + ": must be >= 0");
  if (opt.max_modes < 1) throw InputError(field("max_modes", opt.max_modes) + ": must be >= 1");
  if (!(opt.pencil_fraction > 0.0 && opt.pencil_fraction < 1.0))
    throw InputError(field("pencil_fraction", opt.pencil_fraction) + ": must lie in (0, 1)");
  if (!(opt.rank_tolerance > 0.0 && opt.rank_tolerance < 1.0))
    throw InputError(field("rank_tolerance", opt.rank_tolerance) + ": must lie in (0, 1)");
  const long needed = 3L * (2L * opt.num_modes + 1);
  if (opt.num_modes > 0 && y.size() < needed)
    throw InputError("harmonic_inversion: " + std::to_string(y.size()) + " samples are too few for " +
                     std::to_string(opt.num_modes) + " modes: need at least " + std::to_string(needed));
}

// Right singular vectors and singular values of the (N-L) x (L+1) Hankel
// matrix of y.
Eigen::BDCSVD<MatX> hankel_svd(const VecX& y, int L) {
  const int n = static_cast<int>(y.size());
  MatX H(n - L, L + 1);
  for (int j = 0; j <= L; ++j) H.col(j) = y.segment(j, n - L);
  return Eigen::BDCSVD<MatX>(H, Eigen::ComputeThinV);
}

// Matrix-pencil poles from the M leading right singular vectors, without
// the real pole nearest z = 1 (the offset, fitted separately as a constant).
std::vector<Pole> pencil_poles(const MatX& V, int M, int n) {
  const int L = static_cast<int>(V.rows()) - 1;
  const MatX Vm = V.leftCols(M);
  const MatX Z = Vm.topRows(L).colPivHouseholderQr().solve(Vm.bottomRows(L));
  // The real solver keeps the spectrum of a real matrix conjugate-symmetric
  // exactly: real eigenvalues have imag == 0 and pairs are exact conjugates.
  const Eigen::VectorXcd z = Eigen::EigenSolver<MatX>(Z, false).eigenvalues();
  int offset_pole = -1;
  for (int m = 0; m < M; ++m)
    if (z[m].imag() == 0.0 && (offset_pole < 0 || std::abs(z[m].real() - 1.0) < std::abs(z[offset_pole].real() - 1.0)))
      offset_pole = m;
  std::vector<Pole> poles;
  for (int m = 0; m < M; ++m) {
    if (m == offset_pole || z[m].imag() < 0.0) continue;
    const double r = std::abs(z[m]);
    // A pole that vanishes within a sample carries nothing past y_0, and one
    // that grows by e^700 over the record would overflow its column: both
    // are noise directions, not modes.
    if (r < 1e-8 || std::log(r) * (n - 1) > 700.0) continue;
    poles.push_back({std::log(r), std::arg(z[m]), z[m].imag() == 0.0});
  }
  return poles;
}

}  // namespace

double DampedMode::value(double t) const {
  return amplitude * std::exp(-decay * t) * std::sin(2.0 * kPi * frequency * t + phase);
}

double HarmonicFit::value(double t) const {
  double v = offset;
  for (const DampedMode& m : modes) v += m.value(t);
  return v;
}

HarmonicFit harmonic_inversion(const VecX& samples, double dt, const HarmonicInversionOptions& opt) {
  validate(samples, dt, opt);
  const int n = static_cast<int>(samples.size());
  // Centring keeps a far-from-origin rest position from swamping the
  // oscillation's singular values; the remaining constant is still z = 1.
  const double mean = samples.mean();
  const VecX y = samples.array() - mean;

  HarmonicFit fit;
  fit.offset = mean;
  if (y.norm() <= 1e-13 * samples.norm()) return fit;  // constant up to rounding

  int K = opt.num_modes;
  int L = std::clamp(static_cast<int>(std::lround(opt.pencil_fraction * n)), 1, n - 1);
  if (K > 0) L = std::clamp(L, 2 * K + 1, n - 2 * K - 1);  // validate() ensured n >= 3 (2K+1)
  const Eigen::BDCSVD<MatX> svd = hankel_svd(y, L);
  const VecX& s = svd.singularValues();
  for (Eigen::Index i = 0; i < s.size(); ++i) fit.relative_singular_values.push_back(s[i] / s[0]);
  if (K == 0) {
    // Rank = position of the largest drop s_i / s_{i+1} among the values
    // above the tolerance floor: the edge of the noise floor for a noisy
    // record, the edge of rounding for a clean one.
    const int longest = std::min({L, n - L, n / 3});  // pencil and record limits on M = 2K+1
    const int candidates = std::min({2 * opt.max_modes + 1, longest, static_cast<int>(s.size()) - 1});
    int rank = 0;
    double best_drop = 0.0;
    for (int i = 0; i < candidates && s[i] > opt.rank_tolerance * s[0]; ++i) {
      const double drop = s[i + 1] > 0.0 ? s[i] / s[i + 1] : std::numeric_limits<double>::infinity();
      if (drop > best_drop) best_drop = drop, rank = i + 1;
      if (s[i + 1] == 0.0) break;
    }
    K = std::max(0, std::min({rank / 2, opt.max_modes, (longest - 1) / 2}));
  }
  const std::vector<Pole> poles = K > 0 ? pencil_poles(svd.matrixV(), 2 * K + 1, n) : std::vector<Pole>{};

  // Least squares on the real Vandermonde columns plus a constant.
  int cols = 1;
  for (const Pole& p : poles) cols += p.real ? 1 : 2;
  MatX A(n, cols);
  A.col(0).setOnes();
  for (int k = 0; k < n; ++k) {
    int c = 1;
    for (const Pole& p : poles) {
      const double rk = std::exp(p.log_r * k);
      A(k, c++) = rk * std::cos(p.omega * k);  // (-1)^k for a negative real pole
      if (!p.real) A(k, c++) = rk * std::sin(p.omega * k);
    }
  }
  const VecX coef = A.colPivHouseholderQr().solve(y);
  fit.offset = mean + coef[0];
  fit.rms_residual = std::sqrt((A * coef - y).squaredNorm() / n);

  int c = 1;
  for (const Pole& p : poles) {
    DampedMode m;
    m.decay = -p.log_r / dt;
    m.frequency = p.omega / (2.0 * kPi * dt);
    m.real_pole = p.real;
    // a r^k cos(wk) + b r^k sin(wk) = A r^k sin(wk + theta), A sin(theta) = a,
    // A cos(theta) = b; a real pole is the case b = 0 (theta = +-pi/2).
    const double a = coef[c++];
    const double b = p.real ? 0.0 : coef[c++];
    m.amplitude = std::hypot(a, b);
    m.phase = std::atan2(a, b);
    m.decay_uncertainty = m.amplitude > 0.0 ? std::sqrt(24.0 / n) * fit.rms_residual / (m.amplitude * n * dt)
                                            : std::numeric_limits<double>::infinity();
    fit.modes.push_back(m);
  }
  std::stable_sort(fit.modes.begin(), fit.modes.end(),
                   [](const DampedMode& l, const DampedMode& r) { return l.amplitude > r.amplitude; });
  return fit;
}

const DampedMode& dominant_mode(const HarmonicFit& fit) {
  for (const DampedMode& m : fit.modes)  // sorted by amplitude
    if (!m.real_pole) return m;
  throw NumericalError("harmonic inversion found no oscillating mode (" + std::to_string(fit.modes.size()) +
                       " real poles, rms residual " + std::to_string(fit.rms_residual) + ")");
}

}  // namespace msfab
