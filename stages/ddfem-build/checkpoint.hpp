#pragma once
// The builder's checkpoint (io/checkpoint_file.hpp): the orbits fitted so
// far, rewritten after every round. A resumed build must use the same
// configuration (compared as resolved YAML text).
#include <cstdint>
#include <map>
#include <string>

#include "ddfem/coarse_fit.hpp"
#include "io/checkpoint_file.hpp"

namespace msfab {

using FittedOrbits =
    std::map<std::int64_t, CoarseMaterialFit>;  // orbit representative code (level 2: final representative) -> fit

// All fits in `done` have `points` quadrature points (8 at level 1, 64 at level 2).
void write_checkpoint(const std::string& path, const std::string& config_text, const FittedOrbits& done, int points);
// InputError if the file is unreadable or was written for another config or point count.
FittedOrbits read_checkpoint(const std::string& path, const std::string& config_text, int points);

}  // namespace msfab
