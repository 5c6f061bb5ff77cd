#include "families/structure_distance.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <string>
#include <unsupported/Eigen/FFT>

#include "core/errors.hpp"

namespace msfab {
namespace {

using Complex = std::complex<double>;

int wrap(long long i, int n) { return static_cast<int>(((i % n) + n) % n); }

void require_field(const VoxelField& f, const char* what) {
  if (f.n < 1 || f.values.size() != Eigen::Index(f.n) * f.n * f.n)
    throw InputError(std::string("structure distance: ") + what + " is not an n x n x n field (n = " +
                     std::to_string(f.n) + ", " + std::to_string(f.values.size()) + " values)");
}

// 3D FFT of a real periodic field, built from 1-D transforms. Only the
// half spectrum along x is kept (the field is real, so the other half is
// its conjugate): half the memory and half the work of a complex FFT.
// Layout: spectrum[a + h * (j + n * k)] with h = n / 2 + 1. Eigen's FFT
// keeps plans and scratch buffers inside the object, so each thread needs
// its own instance.
class PeriodicFft {
 public:
  explicit PeriodicFft(int n) : n_(n), h_(n / 2 + 1), in_(n), out_(n) {
    fft_.SetFlag(Eigen::FFT<double>::HalfSpectrum);
  }
  std::size_t spectrum_size() const { return std::size_t(h_) * n_ * n_; }

  void forward(const VecX& values, std::vector<Complex>& spectrum) {
    spectrum.resize(spectrum_size());
    for (int k = 0; k < n_; ++k)
      for (int j = 0; j < n_; ++j) {
        const double* row = values.data() + std::size_t(n_) * (j + std::size_t(n_) * k);
        fft_.fwd(out_.data(), row, n_);
        std::copy(out_.begin(), out_.begin() + h_, spectrum.begin() + std::size_t(h_) * (j + std::size_t(n_) * k));
      }
    transform_yz(spectrum, false);
  }

  // Consumes `spectrum`; the inverse includes the 1 / n^3 scaling.
  void inverse(std::vector<Complex>& spectrum, std::vector<double>& values) {
    transform_yz(spectrum, true);
    values.resize(std::size_t(n_) * n_ * n_);
    for (int k = 0; k < n_; ++k)
      for (int j = 0; j < n_; ++j) {
        const std::size_t line = std::size_t(j) + std::size_t(n_) * k;
        fft_.inv(values.data() + std::size_t(n_) * line, spectrum.data() + std::size_t(h_) * line, n_);
      }
  }

 private:
  void transform_yz(std::vector<Complex>& c, bool inverse) {
    const std::size_t stride[2] = {std::size_t(h_), std::size_t(h_) * n_};
    for (int axis = 0; axis < 2; ++axis) {
      const std::size_t s = stride[axis], other = stride[1 - axis];
      for (int b = 0; b < n_; ++b)
        for (int a = 0; a < h_; ++a) {
          const std::size_t base = std::size_t(a) + other * b;
          for (int t = 0; t < n_; ++t) in_[t] = c[base + s * t];
          if (inverse)
            fft_.inv(out_.data(), in_.data(), n_);
          else
            fft_.fwd(out_.data(), in_.data(), n_);
          for (int t = 0; t < n_; ++t) c[base + s * t] = out_[t];
        }
    }
  }

  int n_, h_;
  Eigen::FFT<double> fft_;
  std::vector<Complex> in_, out_;
};

// sum_x (a(x) - b(x - t))^2, summed directly.
double squared_misfit(const VoxelField& a, const VoxelField& b, const std::array<int, 3>& t) {
  const int n = a.n;
  std::vector<int> src[3];
  for (int axis = 0; axis < 3; ++axis) {
    src[axis].resize(n);
    for (int x = 0; x < n; ++x) src[axis][x] = wrap(static_cast<long long>(x) - t[axis], n);
  }
  double sum = 0.0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j) {
      const double* pa = a.values.data() + a.index(0, j, k);
      const double* pb = b.values.data() + b.index(0, src[1][j], src[2][k]);
      for (int i = 0; i < n; ++i) {
        const double d = pa[i] - pb[src[0][i]];
        sum += d * d;
      }
    }
  return sum;
}

// Picks the translation from the correlation c(t) = sum_x a(x) b(x - t):
// the largest few values (FFT round-off can reorder near-ties, and
// symmetric cells have exact ties) are rescored by the direct sum.
AlignedDistance best_translation(const VoxelField& a, const VoxelField& b, const std::vector<double>& corr) {
  constexpr std::size_t kCandidates = 8;
  const int n = a.n;
  const double cmax = *std::max_element(corr.begin(), corr.end());
  const double tol = 1e-10 * (a.values.squaredNorm() + b.values.squaredNorm());
  std::vector<std::size_t> cand;
  for (std::size_t t = 0; t < corr.size(); ++t)
    if (corr[t] >= cmax - tol) cand.push_back(t);
  auto higher = [&](std::size_t p, std::size_t q) { return corr[p] != corr[q] ? corr[p] > corr[q] : p < q; };
  if (cand.size() > kCandidates) {
    std::partial_sort(cand.begin(), cand.begin() + kCandidates, cand.end(), higher);
    cand.resize(kCandidates);
  }
  std::sort(cand.begin(), cand.end());
  AlignedDistance best;
  double best_sum = 0.0;
  bool first = true;
  for (std::size_t t : cand) {
    const std::array<int, 3> shift{{int(t % n), int((t / n) % n), int(t / (std::size_t(n) * n))}};
    const double sum = squared_misfit(a, b, shift);
    if (first || sum < best_sum) best_sum = sum, best.shift = shift, first = false;
  }
  best.distance = std::sqrt(std::max(0.0, best_sum) / double(a.values.size()));
  return best;
}

// corr = inverse FFT of A conj(B).
void correlate(PeriodicFft& fft, const std::vector<Complex>& A, const std::vector<Complex>& B,
               std::vector<Complex>& product, std::vector<double>& corr) {
  product.resize(A.size());
  for (std::size_t q = 0; q < A.size(); ++q) product[q] = A[q] * std::conj(B[q]);
  fft.inverse(product, corr);
}

void blur_axis(VoxelField& f, int axis, const std::vector<double>& w, int radius) {
  const int n = f.n;
  const std::size_t stride = axis == 0 ? 1 : axis == 1 ? std::size_t(n) : std::size_t(n) * n;
  const std::size_t other[2] = {axis == 0 ? std::size_t(n) : 1, axis == 2 ? std::size_t(n) : std::size_t(n) * n};
  std::vector<double> line(n), out(n);
  for (int b = 0; b < n; ++b)
    for (int a = 0; a < n; ++a) {
      const std::size_t base = other[0] * a + other[1] * b;
      for (int x = 0; x < n; ++x) line[x] = f.values[base + stride * x];
      for (int x = 0; x < n; ++x) {
        double s = 0.0;
        for (int o = -radius; o <= radius; ++o) s += w[o + radius] * line[wrap(static_cast<long long>(x) + o, n)];
        out[x] = s;
      }
      for (int x = 0; x < n; ++x) f.values[base + stride * x] = out[x];
    }
}

}  // namespace

VoxelField solid_indicator(const std::vector<int>& ids, int n) {
  if (n < 1 || ids.size() != std::size_t(n) * n * n)
    throw InputError("structure field: expected " + std::to_string(n) + "^3 voxel ids, got " +
                     std::to_string(ids.size()));
  VoxelField f(n);
  for (std::size_t v = 0; v < ids.size(); ++v) f.values[v] = ids[v] != 0 ? 1.0 : 0.0;
  return f;
}

VoxelField average_pool(const VoxelField& field, int factor) {
  require_field(field, "the pooled field");
  if (factor < 1 || field.n % factor != 0)
    throw InputError("structure field: pool factor " + std::to_string(factor) + " does not divide the cell size " +
                     std::to_string(field.n));
  const int m = field.n / factor;
  VoxelField out(m);
  const double scale = 1.0 / (double(factor) * factor * factor);
  for (int k = 0; k < field.n; ++k)
    for (int j = 0; j < field.n; ++j)
      for (int i = 0; i < field.n; ++i) out.at(i / factor, j / factor, k / factor) += field.at(i, j, k);
  out.values *= scale;
  return out;
}

VoxelField periodic_gaussian_blur(const VoxelField& field, double sigma) {
  require_field(field, "the blurred field");
  if (!(sigma >= 0) || !std::isfinite(sigma))
    throw InputError("structure field: blur sigma must be finite and >= 0, got " + std::to_string(sigma));
  VoxelField out = field;
  if (sigma == 0) return out;
  const int radius = static_cast<int>(std::ceil(4.0 * sigma));
  std::vector<double> w(2 * radius + 1);
  double total = 0.0;
  for (int o = -radius; o <= radius; ++o) total += w[o + radius] = std::exp(-0.5 * (o * o) / (sigma * sigma));
  for (double& x : w) x /= total;
  for (int axis = 0; axis < 3; ++axis) blur_axis(out, axis, w, radius);
  return out;
}

VoxelField smoothed_field(const std::vector<int>& ids, int n, const FieldOptions& options) {
  VoxelField f = solid_indicator(ids, n);
  if (options.pool_factor != 1) f = average_pool(f, options.pool_factor);
  return periodic_gaussian_blur(f, options.sigma);
}

VoxelField translate_field(const VoxelField& field, const std::array<int, 3>& shift) {
  require_field(field, "the translated field");
  const int n = field.n;
  VoxelField out(n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        out.at(wrap(static_cast<long long>(i) + shift[0], n), wrap(static_cast<long long>(j) + shift[1], n),
               wrap(static_cast<long long>(k) + shift[2], n)) = field.at(i, j, k);
  return out;
}

AlignedDistance structure_distance(const VoxelField& a, const VoxelField& b) {
  require_field(a, "the first field");
  require_field(b, "the second field");
  if (a.n != b.n)
    throw InputError("structure distance: fields of different sizes " + std::to_string(a.n) + "^3 and " +
                     std::to_string(b.n) + "^3; pool them to a common size first");
  PeriodicFft fft(a.n);
  std::vector<Complex> A, B, product;
  std::vector<double> corr;
  fft.forward(a.values, A);
  fft.forward(b.values, B);
  correlate(fft, A, B, product, corr);
  return best_translation(a, b, corr);
}

MatX pairwise_structure_distances(const std::vector<VoxelField>& fields) {
  const int m = static_cast<int>(fields.size());
  MatX D = MatX::Zero(m, m);
  if (m == 0) return D;
  for (int i = 0; i < m; ++i) {
    require_field(fields[i], ("field " + std::to_string(i)).c_str());
    if (fields[i].n != fields[0].n)
      throw InputError("structure distance: field " + std::to_string(i) + " is " + std::to_string(fields[i].n) +
                       "^3 but field 0 is " + std::to_string(fields[0].n) + "^3");
  }
  const int n = fields[0].n;
  std::vector<std::vector<Complex>> spectra(m);
#pragma omp parallel
  {
    PeriodicFft fft(n);
#pragma omp for schedule(dynamic)
    for (int i = 0; i < m; ++i) fft.forward(fields[i].values, spectra[i]);
  }
  // Pairs i < j in a flat list so the dynamic schedule balances rows.
  std::vector<std::pair<int, int>> pairs;
  pairs.reserve(std::size_t(m) * (m - 1) / 2);
  for (int i = 0; i < m; ++i)
    for (int j = i + 1; j < m; ++j) pairs.emplace_back(i, j);
  const long long np = static_cast<long long>(pairs.size());
#pragma omp parallel
  {
    PeriodicFft fft(n);
    std::vector<Complex> product;
    std::vector<double> corr;
#pragma omp for schedule(dynamic, 8)
    for (long long p = 0; p < np; ++p) {
      const auto [i, j] = pairs[p];
      correlate(fft, spectra[i], spectra[j], product, corr);
      D(i, j) = D(j, i) = best_translation(fields[i], fields[j], corr).distance;
    }
  }
  return D;
}

}  // namespace msfab
