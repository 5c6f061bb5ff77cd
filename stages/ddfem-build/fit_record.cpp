#include "fit_record.hpp"

namespace msfab {

void pack_fit(const CoarseMaterialFit& fit, double* row) {
  const int P = fit.points();
  double* p = row;
  for (int k = 0; k < 8; ++k) *p++ = fit.material_ids[k];
  for (const auto* values : {&fit.mu, &fit.lambda, &fit.C, &fit.mu0, &fit.lambda0})
    for (int k = 0; k < P; ++k) *p++ = (*values)[k];
  for (int k = 0; k < P; ++k)
    for (int a = 0; a < 3; ++a) *p++ = fit.v[k][a];
  *p++ = fit.fitted;
  *p++ = fit.residual;
  *p++ = fit.objective;
  *p++ = fit.heldout_error;
  *p++ = fit.heldout_energy_error;
  *p++ = fit.samples_attempted;
  *p++ = fit.samples_dropped;
  *p++ = fit.samples_coarse_inverted;
  *p++ = fit.samples_train;
  *p++ = fit.samples_heldout;
  *p++ = fit.seconds;
  *p++ = fit.mu_centre;
  *p++ = fit.lambda_centre;
  *p++ = fit.enhanced;
  *p++ = fit.bubble_rounds;
}

CoarseMaterialFit unpack_fit(const double* row, int points) {
  CoarseMaterialFit fit(points);
  const double* p = row;
  for (int k = 0; k < 8; ++k) fit.material_ids[k] = static_cast<int>(*p++);
  for (auto* values : {&fit.mu, &fit.lambda, &fit.C, &fit.mu0, &fit.lambda0})
    for (int k = 0; k < points; ++k) (*values)[k] = *p++;
  for (int k = 0; k < points; ++k)
    for (int a = 0; a < 3; ++a) fit.v[k][a] = *p++;
  fit.fitted = *p++ != 0;
  fit.residual = *p++;
  fit.objective = *p++;
  fit.heldout_error = *p++;
  fit.heldout_energy_error = *p++;
  fit.samples_attempted = static_cast<int>(*p++);
  fit.samples_dropped = static_cast<int>(*p++);
  fit.samples_coarse_inverted = static_cast<int>(*p++);
  fit.samples_train = static_cast<int>(*p++);
  fit.samples_heldout = static_cast<int>(*p++);
  fit.seconds = *p++;
  fit.mu_centre = *p++;
  fit.lambda_centre = *p++;
  fit.enhanced = *p++ != 0;
  fit.bubble_rounds = static_cast<int>(*p++);
  return fit;
}

}  // namespace msfab
