// Harmonic inversion (matrix pencil), marker-track CSV input and the DAC
// material fit (thesis §4.3.2): exact recovery of synthetic damped sinusoids,
// accuracy under noise, an ODE-integrated oscillator as independent
// reference, the Eq. 4.17/4.18 round trip, and input validation.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "dynamics/dac_calibration.hpp"
#include "dynamics/harmonic_inversion.hpp"
#include "dynamics/marker_track.hpp"

using namespace msfab;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kFps = 240.0;  // the thesis' high-speed video rate

struct Mode {
  double f, d, A, theta;
};

VecX synthesize(const std::vector<Mode>& modes, double offset, int n, double dt) {
  VecX y = VecX::Constant(n, offset);
  for (int k = 0; k < n; ++k)
    for (const Mode& m : modes) y[k] += m.A * std::exp(-m.d * k * dt) * std::sin(2 * kPi * m.f * k * dt + m.theta);
  return y;
}

double rel(double got, double want) { return std::abs(got - want) / std::abs(want); }

void expect_input_error(const std::function<void()>& call, const std::vector<std::string>& fragments) {
  try {
    call();
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    for (const std::string& f : fragments)
      EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << "'" << f << "' not in: " << e.what();
  }
}

// A uniquely named CSV under the test temp directory, removed afterwards.
class TempCsv {
 public:
  explicit TempCsv(const std::string& text) {
    path_ = ::testing::TempDir() + "msfab_marker_" + ::testing::UnitTest::GetInstance()->current_test_info()->name() +
            "_" + std::to_string(::getpid()) + "_" + std::to_string(counter_++) + ".csv";
    std::ofstream(path_) << text;
  }
  ~TempCsv() { std::remove(path_.c_str()); }
  const std::string& path() const { return path_; }

 private:
  static inline int counter_ = 0;
  std::string path_;
};

std::string uniform_csv(int n, const std::string& header = "t,x,y") {
  std::string s = header + "\n";
  for (int k = 0; k < n; ++k) {
    char row[96];
    std::snprintf(row, sizeof row, "%.9f,%.6f,%.6f\n", k / kFps, std::sin(0.1 * k), 2.0 + k);
    s += row;
  }
  return s;
}

}  // namespace

TEST(HarmonicInversion, SingleModeExactWithoutNoise) {
  const double dt = 1.0 / kFps;
  const Mode m{3.2, 0.8, 1.5, 0.7};
  const VecX y = synthesize({m}, 0.3, 480, dt);
  for (int num_modes : {1, 0}) {  // given and chosen from the singular values
    HarmonicInversionOptions opt;
    opt.num_modes = num_modes;
    const HarmonicFit fit = harmonic_inversion(y, dt, opt);
    ASSERT_EQ(fit.modes.size(), 1u) << "num_modes " << num_modes;
    const DampedMode& got = fit.modes[0];
    EXPECT_FALSE(got.real_pole);
    EXPECT_LT(rel(got.frequency, m.f), 1e-9);
    EXPECT_LT(rel(got.decay, m.d), 1e-8);
    EXPECT_LT(rel(got.amplitude, m.A), 1e-9);
    EXPECT_NEAR(got.phase, m.theta, 1e-9);
    EXPECT_NEAR(fit.offset, 0.3, 1e-9);
    EXPECT_LT(fit.rms_residual, 1e-10);
    EXPECT_NEAR(fit.value(0.37), 0.3 + 1.5 * std::exp(-0.8 * 0.37) * std::sin(2 * kPi * 3.2 * 0.37 + 0.7), 1e-9);
  }
}

TEST(HarmonicInversion, TwoModesSortedByAmplitude) {
  const double dt = 1.0 / kFps;
  const Mode low{2.5, 0.5, 1.0, -1.2}, high{11.0, 2.0, 0.4, 2.9};
  const VecX y = synthesize({high, low}, -0.2, 600, dt);
  for (int num_modes : {2, 0}) {
    HarmonicInversionOptions opt;
    opt.num_modes = num_modes;
    const HarmonicFit fit = harmonic_inversion(y, dt, opt);
    ASSERT_EQ(fit.modes.size(), 2u) << "num_modes " << num_modes;
    int i = 0;
    for (const Mode& m : {low, high}) {
      const DampedMode& got = fit.modes[i++];
      EXPECT_LT(rel(got.frequency, m.f), 1e-9);
      EXPECT_LT(rel(got.decay, m.d), 1e-8);
      EXPECT_LT(rel(got.amplitude, m.A), 1e-8);
      EXPECT_NEAR(got.phase, m.theta, 1e-8);
    }
    EXPECT_NEAR(fit.offset, -0.2, 1e-9);
    EXPECT_EQ(&dominant_mode(fit), &fit.modes[0]);
  }
}

// A marker hundreds of units from the origin oscillating by a fraction of a
// unit: the offset must not swamp the automatic order choice.
TEST(HarmonicInversion, LargeOffsetAutomaticOrder) {
  const double dt = 1.0 / kFps;
  const Mode m{4.1, 1.1, 0.5, 0.0};
  const HarmonicFit fit = harmonic_inversion(synthesize({m}, 250.0, 400, dt), dt);
  ASSERT_EQ(fit.modes.size(), 1u);
  EXPECT_LT(rel(fit.modes[0].frequency, m.f), 1e-8);
  EXPECT_LT(rel(fit.modes[0].decay, m.d), 1e-8);
  EXPECT_NEAR(fit.offset, 250.0, 1e-8);
}

TEST(HarmonicInversion, GaussianNoise) {
  const double dt = 1.0 / kFps;
  const Mode m{3.2, 0.8, 1.0, 0.4};
  const VecX clean = synthesize({m}, 0.05, 720, dt);  // 3 s, ~10 periods, decays to 9%
  for (double level : {0.01, 0.03, 0.05}) {
    for (std::uint64_t seed : {1u, 2u}) {
      std::mt19937_64 rng(seed);
      std::normal_distribution<double> noise(0.0, level * m.A);
      VecX y = clean;
      for (int k = 0; k < y.size(); ++k) y[k] += noise(rng);
      HarmonicInversionOptions opt;
      opt.num_modes = 1;
      const HarmonicFit fit = harmonic_inversion(y, dt, opt);
      const DampedMode& got = dominant_mode(fit);
      SCOPED_TRACE("noise " + std::to_string(level) + " seed " + std::to_string(seed));
      EXPECT_LT(rel(got.frequency, m.f), 0.005);
      EXPECT_LT(rel(got.decay, m.d), 0.05);
      EXPECT_LT(rel(got.amplitude, m.A), 0.05);
      // The residual is the noise: the model leaves nothing systematic.
      EXPECT_NEAR(fit.rms_residual, level * m.A, 0.15 * level * m.A);
      // The automatic order sees one mode above the noise floor.
      const HarmonicFit automatic = harmonic_inversion(y, dt);
      ASSERT_EQ(automatic.modes.size(), 1u);
      EXPECT_LT(rel(automatic.modes[0].frequency, m.f), 0.005);
    }
  }
}

// Independent reference: the oscillator of Eq. 4.16 integrated with RK4
// (not the closed form), sampled at video rate; inversion followed by the
// DAC fit must return the eigenvalue and stiffness damping it was run with.
TEST(HarmonicInversion, RecoversIntegratedOscillatorAndCalibration) {
  const double lambda = 1500.0, b = 8e-4;  // f ~ 6.2 Hz, d = 0.6 / s
  const double dt = 1.0 / kFps;
  const int substeps = 20, n = 480;
  const double h = dt / substeps;
  auto accel = [&](double q, double v) { return -b * lambda * v - lambda * q; };
  double q = 0.02, v = 0.0;
  VecX y(n);
  for (int k = 0; k < n; ++k) {
    y[k] = 0.1 + q;
    for (int s = 0; s < substeps; ++s) {
      const double k1q = v, k1v = accel(q, v);
      const double k2q = v + 0.5 * h * k1v, k2v = accel(q + 0.5 * h * k1q, v + 0.5 * h * k1v);
      const double k3q = v + 0.5 * h * k2v, k3v = accel(q + 0.5 * h * k2q, v + 0.5 * h * k2v);
      const double k4q = v + h * k3v, k4v = accel(q + h * k3q, v + h * k3v);
      q += h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q);
      v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
    }
  }
  const DampedMode mode = dominant_mode(harmonic_inversion(y, dt));
  const DacCalibration cal = calibrate_dac(mode.frequency, mode.decay, 600.0, 2.0);
  EXPECT_LT(rel(cal.target_eigenvalue, lambda), 1e-8);  // RK4 error ~1e-10
  EXPECT_LT(rel(cal.damping.b, b), 1e-8);
  EXPECT_EQ(cal.damping.a, 0.0);
  EXPECT_LT(rel(cal.youngs_modulus, lambda / 600.0 * 2.0), 1e-8);
}

TEST(HarmonicInversion, ConstantSignalHasNoMode) {
  const HarmonicFit fit = harmonic_inversion(VecX::Constant(64, 3.5), 0.01);
  EXPECT_TRUE(fit.modes.empty());
  EXPECT_DOUBLE_EQ(fit.offset, 3.5);
  EXPECT_THROW(dominant_mode(fit), NumericalError);
}

TEST(HarmonicInversion, RejectsBadInput) {
  const VecX y = synthesize({{3.0, 0.5, 1.0, 0.0}}, 0.0, 100, 0.01);
  expect_input_error([&] { harmonic_inversion(y.head(10), 0.01); }, {"10 samples", "at least 16"});
  expect_input_error([&] { harmonic_inversion(y, 0.0); }, {"sample_interval"});
  VecX bad = y;
  bad[17] = std::numeric_limits<double>::quiet_NaN();
  expect_input_error([&] { harmonic_inversion(bad, 0.01); }, {"sample 17", "not finite"});
  HarmonicInversionOptions opt;
  opt.num_modes = 20;  // needs 3 * 41 samples
  expect_input_error([&] { harmonic_inversion(y, 0.01, opt); }, {"too few", "20 modes"});
  opt = {};
  opt.pencil_fraction = 1.0;
  expect_input_error([&] { harmonic_inversion(y, 0.01, opt); }, {"pencil_fraction"});
}

TEST(DacCalibration, RoundTripThroughModalResponse) {
  for (double lambda : {3.7, 1234.5, 2.5e6}) {
    for (double b : {0.0, 1e-5, 3e-4}) {
      const ModalResponse r = modal_response(lambda, {0.0, b});
      ASSERT_TRUE(r.underdamped);
      EXPECT_DOUBLE_EQ(r.decay, 0.5 * b * lambda);
      const DacCalibration cal = calibrate_dac(r.frequency, r.decay, 0.25 * lambda, 1.0);
      EXPECT_LT(rel(cal.target_eigenvalue, lambda), 1e-12);
      EXPECT_NEAR(cal.damping.b, b, 1e-12 * std::max(b, 1e-6));
      EXPECT_EQ(cal.damping.a, 0.0);
      EXPECT_LT(rel(cal.stiffness_scale, 4.0), 1e-12);
      EXPECT_LT(rel(cal.youngs_modulus, 4.0), 1e-12);
      // Scaling the coarse spectrum puts the fundamental on target (Eq. 4.18).
      const auto modes = calibrated_modes({0.25 * lambda, 0.75 * lambda}, cal);
      EXPECT_LT(rel(modes[0].frequency, r.frequency), 1e-12);
      EXPECT_NEAR(modes[1].decay, 3.0 * r.decay, 1e-12 * r.decay);
    }
  }
}

TEST(DacCalibration, OverdampedModeAndBadInput) {
  const ModalResponse r = modal_response(4.0, {0.0, 2.0});  // d = 4 > sqrt(4)
  EXPECT_FALSE(r.underdamped);
  EXPECT_EQ(r.frequency, 0.0);
  EXPECT_DOUBLE_EQ(r.decay, 4.0);
  EXPECT_TRUE(modal_response(4.0, {1.0, 0.0}).underdamped);  // d = 0.5
  expect_input_error([] { calibrate_dac(0.0, 1.0, 10.0); }, {"target frequency"});
  expect_input_error([] { calibrate_dac(2.0, -0.1, 10.0); }, {"target decay"});
  expect_input_error([] { calibrate_dac(2.0, 0.1, 0.0); }, {"coarse eigenvalue"});
  expect_input_error([] { calibrate_dac(std::nan(""), 0.1, 1.0); }, {"target frequency", "finite"});
  expect_input_error([] { modal_response(-1.0, {}); }, {"eigenvalue"});
  expect_input_error([] { modal_response(1.0, {0.0, -1.0}); }, {"rayleigh b"});
}

TEST(MarkerTrack, ReadsSelectedColumn) {
  TempCsv csv("# rig 3, camera A\n" + uniform_csv(20) + "\n");
  const MarkerTrack track = read_marker_track(csv.path(), "y");
  EXPECT_EQ(track.column, "y");
  EXPECT_EQ(track.source, csv.path());
  ASSERT_EQ(track.values.size(), 20);
  EXPECT_DOUBLE_EQ(track.values[7], 9.0);
  EXPECT_NEAR(track.times[19], 19 / kFps, 1e-9);
  EXPECT_NEAR(track.sample_interval, 1 / kFps, 1e-9);  // times written with 9 decimals

  // Single coordinate, CRLF line ends, blanks around cells.
  std::string s = "Time , z\r\n";
  for (int k = 0; k < 16; ++k) s += " " + std::to_string(0.5 * k) + " , " + std::to_string(k * k) + "\r\n";
  TempCsv crlf(s);
  const MarkerTrack z = read_marker_track(crlf.path());
  EXPECT_EQ(z.column, "z");
  EXPECT_DOUBLE_EQ(z.values[15], 225.0);
  EXPECT_DOUBLE_EQ(z.sample_interval, 0.5);
}

TEST(MarkerTrack, TrackToFrequency) {
  const Mode m{5.0, 0.7, 2.0, 1.0};
  const VecX y = synthesize({m}, 41.0, 300, 1 / kFps);
  std::string s = "time,x\n";
  for (int k = 0; k < y.size(); ++k) {
    char row[64];
    std::snprintf(row, sizeof row, "%.10f,%.12f\n", 1.5 + k / kFps, y[k]);
    s += row;
  }
  TempCsv csv(s);
  const MarkerTrack track = read_marker_track(csv.path(), "x");
  const DampedMode got = dominant_mode(harmonic_inversion(track.values, track.sample_interval));
  EXPECT_LT(rel(got.frequency, m.f), 1e-7);
  EXPECT_LT(rel(got.decay, m.d), 1e-6);
}

TEST(MarkerTrack, RejectsBadFiles) {
  const std::string missing = ::testing::TempDir() + "msfab_no_such_track.csv";
  expect_input_error([&] { read_marker_track(missing, "x"); }, {missing, "no such file"});

  std::string text = uniform_csv(20);
  const auto line_start = [&](int line) {  // 1-based
    std::string::size_type p = 0;
    for (int i = 1; i < line; ++i) p = text.find('\n', p) + 1;
    return p;
  };
  {
    std::string t = text;
    const auto p = line_start(4), q = t.find(',', p) + 1;
    t.replace(q, t.find(',', q) - q, "nan");
    TempCsv csv(t);
    expect_input_error([&] { read_marker_track(csv.path(), "x"); }, {csv.path(), "line 4", "'x'", "finite"});
    // The broken column is not read when another one is selected.
    EXPECT_NO_THROW(read_marker_track(csv.path(), "y"));
  }
  {
    std::string t = text;
    const auto p = line_start(6), q = t.find(',', p) + 1;
    t.replace(q, t.find(',', q) - q, "0.1.2");
    TempCsv csv(t);
    expect_input_error([&] { read_marker_track(csv.path(), "x"); }, {csv.path(), "line 6", "'x'", "not a number"});
  }
  {
    TempCsv csv(uniform_csv(10));
    expect_input_error([&] { read_marker_track(csv.path(), "x"); }, {csv.path(), "10 samples", "at least 16"});
  }
  {
    TempCsv csv(text);
    expect_input_error([&] { read_marker_track(csv.path(), "z"); }, {csv.path(), "'z'", "'x', 'y'"});
    expect_input_error([&] { read_marker_track(csv.path()); }, {csv.path(), "choose a coordinate"});
  }
  {
    TempCsv csv(uniform_csv(20, "frame,x"));
    expect_input_error([&] { read_marker_track(csv.path(), "x"); }, {csv.path(), "no time column"});
  }
  {
    std::string t = text;
    const auto p = line_start(9);  // sample 7: time moved by 2% of a frame
    t.replace(p, t.find(',', p) - p, std::to_string(7.02 / kFps));
    TempCsv csv(t);
    expect_input_error([&] { read_marker_track(csv.path(), "x"); }, {csv.path(), "line 9", "uniform"});
  }
  {
    std::string t = text;
    const auto p = line_start(9);  // a repeated frame
    t.replace(p, t.find(',', p) - p, std::to_string(6 / kFps));
    TempCsv csv(t);
    expect_input_error([&] { read_marker_track(csv.path(), "x"); }, {csv.path(), "line 9", "does not increase"});
  }
  {
    std::string t = text;
    t.insert(line_start(5), "0.5,1.0\n");
    TempCsv csv(t);
    expect_input_error([&] { read_marker_track(csv.path(), "x"); }, {csv.path(), "line 5", "2 cells"});
  }
}

// An undamped mode in white noise: the fitted decays scatter about zero
// with the spread the reported standard error predicts (the Cramer-Rao
// bound), so "within three standard errors of zero" is a sound test for an
// undamped rig, and a light but real damping stands out of it.
TEST(HarmonicInversion, DecayUncertaintyPredictsTheScatterOfAnUndampedMode) {
  const double dt = 1.0 / kFps;
  const int n = 720;
  // One mode of decay d in white noise of 2% of its amplitude, fitted.
  const auto fitted = [&](double d, int seed) {
    VecX y = synthesize({{7.3, d, 1.0, 0.4}}, 0.0, n, dt);
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0.0, 0.02);
    for (int k = 0; k < n; ++k) y[k] += noise(rng);
    HarmonicInversionOptions opt;
    opt.num_modes = 1;
    return dominant_mode(harmonic_inversion(y, dt, opt));  // a copy of the mode
  };
  double sum_sq = 0, mean_uncertainty = 0;
  int within_three = 0;
  const int trials = 60;
  for (int seed = 1; seed <= trials; ++seed) {
    const DampedMode m = fitted(0.0, seed);
    sum_sq += m.decay * m.decay;
    mean_uncertainty += m.decay_uncertainty / trials;
    if (std::abs(m.decay) <= 3 * m.decay_uncertainty) ++within_three;
  }
  const double scatter = std::sqrt(sum_sq / trials);
  EXPECT_GT(scatter, 0.5 * mean_uncertainty);
  EXPECT_LT(scatter, 2.0 * mean_uncertainty);
  EXPECT_GE(within_three, trials - 2);
  // The same record with d = 0.3 1/s (the amplitude falls 26% over it).
  const DampedMode damped = fitted(0.3, 7);
  EXPECT_GT(damped.decay, 10 * damped.decay_uncertainty);
}
