#include "fit_record.hpp"

#include <stdexcept>

namespace msfab {

void pack_fit(const CoarseMaterialFit& fit, double* row) {
  if (fit.points() != 8) throw std::invalid_argument("pack_fit: level-1 fits have 8 points");
  double* p = row;
  for (int k = 0; k < 8; ++k) *p++ = fit.material_ids[k];
  for (int k = 0; k < 8; ++k) *p++ = fit.mu[k];
  for (int k = 0; k < 8; ++k) *p++ = fit.lambda[k];
  for (int k = 0; k < 8; ++k) *p++ = fit.C[k];
  for (int k = 0; k < 8; ++k) *p++ = fit.mu0[k];
  for (int k = 0; k < 8; ++k) *p++ = fit.lambda0[k];
  for (int k = 0; k < 8; ++k)
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
  *p++ = 0;
  *p++ = 0;
}

CoarseMaterialFit unpack_fit(const double* row) {
  CoarseMaterialFit fit(8);
  const double* p = row;
  for (int k = 0; k < 8; ++k) fit.material_ids[k] = static_cast<int>(*p++);
  for (int k = 0; k < 8; ++k) fit.mu[k] = *p++;
  for (int k = 0; k < 8; ++k) fit.lambda[k] = *p++;
  for (int k = 0; k < 8; ++k) fit.C[k] = *p++;
  for (int k = 0; k < 8; ++k) fit.mu0[k] = *p++;
  for (int k = 0; k < 8; ++k) fit.lambda0[k] = *p++;
  for (int k = 0; k < 8; ++k)
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
  return fit;
}

}  // namespace msfab
