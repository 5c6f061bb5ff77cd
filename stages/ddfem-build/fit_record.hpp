#pragma once
// A coarse-material fit as a fixed-length row of doubles: what ranks send to
// rank 0 and what the checkpoint stores. Bit-exact round trip.
#include <vector>

#include "ddfem/coarse_fit.hpp"

namespace msfab {

// 8 ids, then mu, lambda, C, mu0, lambda0 and v (3) per point, then 15 scalars.
constexpr int fit_record_size(int points) { return 8 + 8 * points + 15; }
void pack_fit(const CoarseMaterialFit& fit, double* row);  // fit_record_size(fit.points()) values
CoarseMaterialFit unpack_fit(const double* row, int points);

}  // namespace msfab
