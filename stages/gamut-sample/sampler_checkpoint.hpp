#pragma once
// The sampler's checkpoint (io/checkpoint_file.hpp), rewritten after every
// cycle: the whole SamplerState. A resumed run must use the
// same configuration and seed (compared as text) and continues with the
// next cycle; since every random draw is keyed by (seed, cycle, item), the
// result equals an uninterrupted run.
#include <string>

#include "io/checkpoint_file.hpp"
#include "sampler.hpp"

namespace msfab {

void write_sampler_checkpoint(const std::string& path, const std::string& run_text, const SamplerState& state);
// InputError if unreadable or written for another configuration.
SamplerState read_sampler_checkpoint(const std::string& path, const std::string& run_text);

}  // namespace msfab
