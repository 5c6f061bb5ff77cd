#include "dynamics/dac_calibration.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "core/errors.hpp"

namespace msfab {
namespace {

constexpr double kTwoPi = 6.28318530717958647692;

void require(bool ok, const char* where, const char* name, double value, const char* rule) {
  if (ok && std::isfinite(value)) return;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", value);
  throw InputError(std::string(where) + ": " + name + " = " + buf + ": must be " + rule + " and finite");
}

}  // namespace

ModalResponse modal_response(double lambda, const RayleighDamping& damping) {
  require(lambda > 0.0, "modal_response", "eigenvalue", lambda, "positive");
  require(damping.a >= 0.0, "modal_response", "rayleigh a", damping.a, ">= 0");
  require(damping.b >= 0.0, "modal_response", "rayleigh b", damping.b, ">= 0");
  ModalResponse r;
  r.decay = 0.5 * (damping.a + damping.b * lambda);
  const double w2 = lambda - r.decay * r.decay;
  r.underdamped = w2 > 0.0;
  r.frequency = r.underdamped ? std::sqrt(w2) / kTwoPi : 0.0;
  return r;
}

DacCalibration calibrate_dac(double f_t, double d_t, double lambda_0, double modulus) {
  require(f_t > 0.0, "calibrate_dac", "target frequency", f_t, "positive");
  require(d_t >= 0.0, "calibrate_dac", "target decay", d_t, ">= 0");
  require(lambda_0 > 0.0, "calibrate_dac", "coarse eigenvalue", lambda_0, "positive");
  require(modulus > 0.0, "calibrate_dac", "reference Young's modulus", modulus, "positive");
  DacCalibration c;
  const double w = kTwoPi * f_t;
  c.target_eigenvalue = w * w + d_t * d_t;
  c.damping = {0.0, 2.0 * d_t / c.target_eigenvalue};
  c.stiffness_scale = c.target_eigenvalue / lambda_0;
  c.youngs_modulus = c.stiffness_scale * modulus;
  return c;
}

std::vector<ModalResponse> calibrated_modes(const std::vector<double>& coarse_eigenvalues,
                                            const DacCalibration& calibration) {
  std::vector<ModalResponse> out;
  for (double lambda : coarse_eigenvalues) {
    require(lambda > 0.0, "calibrated_modes", "coarse eigenvalue", lambda, "positive");
    out.push_back(modal_response(calibration.stiffness_scale * lambda, calibration.damping));
  }
  return out;
}

}  // namespace msfab
