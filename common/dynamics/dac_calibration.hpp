#pragma once
// Material fitting of Dynamics-Aware Coarsening (thesis §4.3.2, Eq. 4.16-4.18).
// A coarse mesh is numerically too stiff; rather than refine it, its
// spectrum is calibrated to a measured vibration. Each linear mode m_i of
// K q = lambda M q with Rayleigh damping C = a M + b K obeys (Eq. 4.16)
//   m_i'' = -(a + b lambda_i) m_i' - lambda_i m_i,
// i.e. m_i(t) = A_i exp(-d_i t) sin(2 pi f_i t + theta_i) with (Eq. 4.17)
//   d_i = (a + b lambda_i) / 2,   f_i = sqrt(lambda_i - d_i^2) / (2 pi).
// Inverting with the tracked f_t, d_t and a = 0 (the thesis observes
// negligible mass damping) gives
//   lambda_t = (2 pi f_t)^2 + d_t^2,   b = 2 d_t / lambda_t,
// and since K is linear in Young's modulus with M fixed, the modulus that
// moves the coarse fundamental eigenvalue lambda_1^0 (computed with E_m) onto
// lambda_t is (Eq. 4.18)
//   E_n = (lambda_t / lambda_1^0) E_m.
// Units: lambda in rad^2/s^2 (K and M in consistent SI units), f in Hz,
// d in 1/s, b in s, a in 1/s.
#include <vector>

namespace msfab {

// Rayleigh damping C = a M + b K.
struct RayleighDamping {
  double a = 0.0;  // mass-proportional, 1/s
  double b = 0.0;  // stiffness-proportional, s
};

// Free response of one mode (Eq. 4.17).
struct ModalResponse {
  double frequency = 0.0;  // Hz; 0 when not underdamped
  double decay = 0.0;      // 1/s
  // false when d^2 >= lambda (critically or overdamped): the mode creeps
  // back without oscillating and has no frequency to match.
  bool underdamped = true;
};

// InputError unless lambda > 0, a >= 0, b >= 0, all finite.
ModalResponse modal_response(double lambda, const RayleighDamping& damping);

struct DacCalibration {
  double target_eigenvalue = 0.0;  // lambda_t
  RayleighDamping damping;         // a = 0, b = 2 d_t / lambda_t
  double stiffness_scale = 0.0;    // lambda_t / lambda_1^0 = E_n / E_m
  double youngs_modulus = 0.0;     // E_n
};

// From the tracked fundamental (f_t Hz, d_t 1/s), the coarse mesh's first
// non-rigid eigenvalue lambda_1^0 and the modulus E_m it was computed with.
// InputError unless f_t > 0, d_t >= 0, lambda_1^0 > 0, E_m > 0, all finite.
DacCalibration calibrate_dac(double target_frequency, double target_decay, double coarse_eigenvalue,
                             double reference_modulus = 1.0);

// Modes of the calibrated coarse mesh: lambda_i = stiffness_scale * lambda_i^0
// with the calibrated damping. InputError for a non-positive eigenvalue
// (rigid modes must be left out).
std::vector<ModalResponse> calibrated_modes(const std::vector<double>& coarse_eigenvalues,
                                            const DacCalibration& calibration);

}  // namespace msfab
