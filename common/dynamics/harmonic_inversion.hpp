#pragma once
// Harmonic inversion of a tracked trajectory (thesis §4.3.2): recover the
// damped sinusoids
//   y(t_k) = offset + sum_i A_i exp(-d_i t_k) sin(2 pi f_i t_k + theta_i) + noise,
//   t_k = k dt,
// from N uniform real samples. The thesis cites filter diagonalization
// (Mandelshtam & Taylor 1997); we use the matrix-pencil method (Hua & Sarkar
// 1990), which solves the same harmonic-inversion problem for short records
// with a plain SVD + small eigenproblem and no frequency window to tune:
//  1. Hankel matrix Y (N-L rows, L+1 columns), Y(i, j) = y_{i+j}, with pencil
//     parameter L ~ 0.4 N (Hua & Sarkar: N/3..N/2 minimizes noise variance).
//  2. Thin SVD; keep the M dominant right singular vectors V (rank
//     truncation filters the noise, the "total least squares" pencil).
//  3. Poles z_m = eigenvalues of V1^+ V2, where V1 / V2 are V without its
//     last / first row (the shift invariance of a sum of exponentials).
//  4. Amplitudes, phases and the offset by linear least squares on the
//     Vandermonde columns z_m^k, written in real form (r^k cos, r^k sin) so
//     the fit of a real signal is real by construction.
// The constant offset is the pole z = 1. The signal is centred first (which
// keeps the offset from dominating the singular values of a marker track far
// from the origin), the pencil order is M = 2K + 1 for K sinusoids, the real
// eigenvalue nearest 1 is taken as the offset pole, and a constant column is
// always part of the least-squares fit. A real odd-sized pencil always has a
// real eigenvalue, so the other 2K poles can pair up.
// Limits: frequencies must lie below Nyquist 1/(2 dt); modes closer in
// frequency than ~1/(N dt) are not separated; with noise the decay rate is
// the least accurate quantity (it needs several periods of visible decay).
// Amplitudes and phases refer to t = 0 at the first sample.
#include <vector>

#include "core/types.hpp"

namespace msfab {

struct DampedMode {
  double frequency = 0.0;  // Hz, in [0, 1/(2 dt)]
  double decay = 0.0;      // 1/s; negative for a growing mode
  // Standard error of `decay` if the fit's residual were white noise:
  // sqrt(24 / N) rms / (A N dt), the Cramer-Rao bound of a sinusoid's
  // frequency, which its decay shares for light damping. A decay within a
  // few of these of zero cannot be told from an undamped mode.
  double decay_uncertainty = 0.0;
  double amplitude = 0.0;  // A >= 0 at the first sample
  double phase = 0.0;      // theta in (-pi, pi]
  // A real pole: a pure exponential (f = 0) or a sample-to-sample
  // alternation (f = Nyquist); not a resolved oscillation.
  bool real_pole = false;
  double value(double t) const;
};

struct HarmonicFit {
  std::vector<DampedMode> modes;  // largest amplitude first
  double offset = 0.0;            // rest position
  double rms_residual = 0.0;      // sqrt(mean((y - fit)^2)), signal units
  // Singular values of the Hankel matrix divided by the largest, for
  // judging the model order (a gap after 2K+1 values).
  std::vector<double> relative_singular_values;
  double value(double t) const;
};

struct HarmonicInversionOptions {
  // Damped sinusoids to fit. 0 chooses K = floor(r / 2), where the rank r
  // is placed at the largest ratio between consecutive singular values
  // among those above rank_tolerance * largest, K capped by max_modes and by
  // the record length. The largest drop marks the noise floor when the
  // modes stand well above it; a mode within a few times the noise floor,
  // or a weak mode far below a strong one, can be missed, so give num_modes
  // when the count is known (e.g. the fundamental of a calibration rig).
  int num_modes = 0;
  int max_modes = 8;
  double pencil_fraction = 0.4;  // L = round(fraction * N), in (0, 1)
  double rank_tolerance = 1e-3;
};

// InputError for dt <= 0 or non-finite, fewer than 16 samples, non-finite
// samples, an explicit num_modes needing more than N / 3 pencil rows
// (N < 3 (2K + 1)), or invalid options.
HarmonicFit harmonic_inversion(const VecX& samples, double sample_interval,
                               const HarmonicInversionOptions& options = {});

// The largest-amplitude oscillating mode (real poles skipped). NumericalError
// if the fit has none, e.g. a signal without a resolved oscillation.
const DampedMode& dominant_mode(const HarmonicFit& fit);

}  // namespace msfab
