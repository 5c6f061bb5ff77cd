#pragma once
// A coarse-material fit as a fixed-length row of doubles: what ranks send to
// rank 0 and what the checkpoint stores. Bit-exact round trip.
#include <vector>

#include "ddfem/coarse_fit.hpp"

namespace msfab {

constexpr int kFitRecordSize = 8 * 6 + 24 + 13;

void pack_fit(const CoarseMaterialFit& fit, double* row);
CoarseMaterialFit unpack_fit(const double* row);

}  // namespace msfab
